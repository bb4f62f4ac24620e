"""Certified swarm design (issue 13): exact designer, trade curve, failures, separation.

Every result is checked against the brute-force oracles of ``tests/design_oracle.py``
on the real eros001708 (paper and strict mode) and on random toy instances.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from design_oracle import (best_triple, min_tolerant_size, pair_coverage, subset_coverage)
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.design import (CandidateBank, build_bank, coverage_curve, failure_tolerant,
                              max_coverage, min_swarm, worst_failure)
from ideas_hpc.base.errors import InputError
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.design.ga.genetic import separate_angles

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = ROOT / "campaigns" / "eros-nadir.toml"
STRICT = ['coverage.mode="exact"', "coverage.occlusion=true", "coverage.min_elevation_deg=5.0"]
EPS = 1e-3
_BANKS: dict = {}


def eros_bank(strict: bool, step_deg: float) -> CandidateBank:
    key = (strict, step_deg)
    if key not in _BANKS:
        setup = setup_from_campaign(load(CAMPAIGN, STRICT if strict else []))
        _BANKS[key] = build_bank(setup, np.deg2rad(step_deg))
    return _BANKS[key]


def _need(bank):
    return min(1.0, bank.reach) - EPS


@pytest.mark.parametrize("strict", [False, True], ids=["paper", "strict"])
def test_exact_design_is_minimal_against_all_pairs(eros1708, strict):
    """At 0.5 deg: no single (and, when N = 3, no pair) reaches the target; N reached."""
    bank = eros_bank(strict, 0.5)
    need = _need(bank)
    res = min_swarm(bank, target=need + EPS, eps_tol=EPS, n_max=20, min_separation=1e3)
    assert res.status == "optimal" and res.gap == 0.0 and res.bound == res.n
    assert subset_coverage(bank.masks, bank.areas, res.indices[None, :])[0] >= need - 1e-12
    pairs = pair_coverage(bank.masks, bank.areas)
    best_pair = pairs[np.triu_indices_from(pairs, 1)].max()
    assert np.diag(pairs).max() < need
    assert res.n == (2 if best_pair >= need - 1e-12 else 3)
    assert res.n == (3 if strict else 2)   # the paper's GA reported 3 in paper mode
    curve = coverage_curve(bank, 4)
    assert curve.coverage[0] == pytest.approx(np.diag(pairs).max(), abs=1e-12)
    assert curve.coverage[1] == pytest.approx(best_pair, abs=1e-12)
    assert all(s == "optimal" for s in curve.status) and np.all(np.diff(curve.coverage) >= 0)


@pytest.mark.slow
@pytest.mark.parametrize("strict", [False, True], ids=["paper", "strict"])
def test_best_triple_on_1deg_grid(eros1708, strict):
    """Max-coverage N = 3 equals the exhaustive search over every triple of a 1 deg grid."""
    bank = eros_bank(strict, 1.0)
    best, arg = best_triple(bank.masks, bank.areas)
    r = max_coverage(bank, 3)
    assert r.status == "optimal" and r.gap == 0.0
    assert r.coverage == pytest.approx(best, abs=1e-12)
    res = min_swarm(bank, target=min(1.0, bank.reach), eps_tol=EPS)
    assert (res.n <= 3) == (best >= _need(bank) - 1e-12)


def test_failure_tolerance_against_enumeration(eros1708):
    """k = 1 on a 15 deg grid: the designer's N equals brute force over all swarms and failures."""
    bank = eros_bank(False, 15.0)
    need = _need(bank)
    n_true, swarm = min_tolerant_size(bank.masks, bank.areas, need, 1, 6)
    # a limit far above what this needs (well under a second): optimality is asserted
    res = failure_tolerant(bank, 1, target=need + EPS, eps_tol=EPS, n_max=8, time_limit=600)
    assert res.status == "optimal" and res.gap == 0.0
    assert res.n == n_true and res.bound == n_true
    worst, failed, covs, subsets = worst_failure(bank, res.indices, 1)
    expect = subset_coverage(bank.masks, bank.areas,
                             np.array([[j for j in res.indices if j != f[0]] for f in subsets]))
    assert np.allclose(covs, expect, atol=1e-12) and worst == pytest.approx(expect.min())
    assert worst >= need - 1e-12 and res.worst_failure_coverage == worst
    assert failed[0] == subsets[np.argmin(expect)][0]


def _toy(seed=1, k=14, v=80, p=0.3):
    rng = np.random.default_rng(seed)
    masks = rng.uniform(size=(k, v)) < p
    step = 2 * np.pi / k
    return CandidateBank(theta=step * np.arange(k), masks=masks, areas=rng.uniform(1, 3, v),
                         step_rad=step, d_sep_m=1e4)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_toy_min_swarm_separation_and_curve(seed):
    bank = _toy(seed)
    target = bank.reach
    all_sets = [np.array(c) for n in range(1, 8)
                for c in itertools.combinations(range(bank.n_candidates), n)]
    covs = bank.coverage(all_sets)
    for sep in (0.0, 1e4 * bank.step_rad * 1.5):    # 1.5 steps: neighbours conflict
        gap_ok = [s for s, c in zip(all_sets, covs) if c >= target - 0.02 - 1e-12
                  and (sep == 0 or _separated(s, bank.n_candidates, 1))]
        if not gap_ok:
            with pytest.raises(InputError, match="without the separation") as ei:
                min_swarm(bank, target=target, eps_tol=0.02, min_separation=sep)
            assert ei.value.field == "min_separation"
            continue
        res = min_swarm(bank, target=target, eps_tol=0.02, min_separation=sep)
        assert res.n == min(len(s) for s in gap_ok) and res.status == "optimal"
        if sep:
            assert _separated(res.indices, bank.n_candidates, 1)
    curve = coverage_curve(bank, 5)
    for n in range(1, 6):
        assert curve.coverage[n - 1] == pytest.approx(
            max(c for s, c in zip(all_sets, covs) if len(s) <= n), abs=1e-12)


def _separated(s, n, m):
    s = np.sort(np.asarray(s))
    if s.size < 2:
        return True
    d = np.diff(np.r_[s, s[0] + n])
    return bool(np.all(d > m))


def test_toy_failure_tolerance_k2():
    bank = _toy(4, k=10, v=60, p=0.45)
    need = bank.reach - 0.05
    n_true, _ = min_tolerant_size(bank.masks, bank.areas, need, 2, 8)
    res = failure_tolerant(bank, 2, target=need + 0.05, eps_tol=0.05, n_max=9, time_limit=600)
    assert res.status == "optimal" and res.gap == 0.0
    assert res.n == n_true and res.bound == n_true
    assert res.worst_failure_coverage >= need - 1e-12
    # every pair of failures leaves the target (brute force over the chosen swarm)
    for f in itertools.combinations(res.indices.tolist(), 2):
        rest = np.array([[j for j in res.indices if j not in f]])
        assert subset_coverage(bank.masks, bank.areas, rest)[0] >= need - 1e-12


def test_bad_design_input_names_the_field():
    cases = [(["design.angle_step_deg=0"], "design.angle_step_deg"),
             (["design.angle_step_deg=91"], "design.angle_step_deg"),
             (["design.failures_tolerated=20"], "design.failures_tolerated"),
             (["design.time_limit_s=0"], "design.time_limit_s"),
             (['design.method="annealing"'], "design.method"),
             (["swarm.min_separation_km=-1"], "swarm.min_separation_km")]
    for sets, field in cases:
        with pytest.raises(InputError) as ei:
            load(CAMPAIGN, sets)
        assert ei.value.field == field, sets
    bank = _toy(1)
    with pytest.raises(InputError, match="highest coverage") as ei:
        min_swarm(bank, target=1.0, eps_tol=0.0) if bank.reach < 1 else \
            min_swarm(bank, target=1.5, eps_tol=0.0)
    with pytest.raises(InputError, match="N_max too small: no swarm of at most 1 ") as ei:
        min_swarm(bank, target=bank.reach, eps_tol=0.0, n_max=1)
    assert ei.value.field == "n_max" and ei.value.message.endswith("raise `n_max`")
    best1 = max(bank.coverage([[k] for k in range(bank.n_candidates)]))   # enumeration
    assert f"the best with 1 is {100 * best1:.3f} %;" in ei.value.message
    assert "time_limit" not in ei.value.message                 # proven: not the cause
    with pytest.raises(InputError) as ei:
        min_swarm(bank, target=bank.reach, eps_tol=0.0, min_separation=1e9)
    assert ei.value.field == "min_separation"
    with pytest.raises(InputError) as ei:
        min_swarm(bank, target=bank.reach, eps_tol=0.0, time_limit=0)
    assert ei.value.field == "time_limit"
    with pytest.raises(InputError) as ei:
        failure_tolerant(bank, 3, target=bank.reach, eps_tol=0.0, n_max=3)
    assert ei.value.field == "k"


def test_designer_errors_map_to_the_file_keys():
    """The designers name their own parameters; the campaign layer's map gives the file's
    keys, in the field and in the message (the user's line is unchanged)."""
    from ideas_hpc.campaign.schema.design_checks import designer_errors

    bank = _toy(1)
    cases = [(dict(n_max=1), "design.n_max"), (dict(min_separation=1e9), "swarm.min_separation_km"),
             (dict(time_limit=0), "design.time_limit_s")]
    for kw, key in cases:
        with pytest.raises(InputError) as ei, designer_errors():
            min_swarm(bank, target=bank.reach, eps_tol=0.0, **kw)
        assert ei.value.field == key and "`" not in ei.value.message, kw
    with pytest.raises(InputError) as ei, designer_errors():
        min_swarm(bank, target=bank.reach, eps_tol=0.0, n_max=1)
    assert ei.value.message.endswith("raise design.n_max")
    with pytest.raises(InputError) as ei, designer_errors():
        failure_tolerant(bank, 3, target=bank.reach, eps_tol=0.0, n_max=3)
    assert ei.value.field == "design.failures_tolerated"
    assert ei.value.message == "3 failures need more than design.n_max = 3 spacecraft"


def test_ga_separation_repair():
    step = 0.01
    g = np.array([[3, 1.0, 1.0, 1.02, 5.0], [2, 0.5, 3.0, 9.0, 9.0], [4, 0.0, 1.0, 2.0, 6.28]])
    out = separate_angles(g, 0.05, step)
    assert np.array_equal(out[1], g[1])                       # already separated
    for row in out:
        n = int(row[0])
        a = np.sort(row[1:1 + n])
        d = np.diff(np.r_[a, a[0] + 2 * np.pi])
        assert n == 1 or np.all(d >= 0.05 - 1e-9)
    assert out[0, 0] == 3 and np.allclose(np.sort(out[0, 1:4]), [1.0, 1.05, 1.1])
    assert out[2, 0] == 3                                     # 6.28 is too close to 0.0


def test_exact_campaign_store_same_on_1_and_2_workers(tmp_path):
    from ideas_hpc.campaign.run import run_file

    sets = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3",
            "flyby.z_stop_km=3", "design.angle_step_deg=5", "design.n_max=6"]
    a = xr.open_zarr(run_file(CAMPAIGN, out=tmp_path / "a.zarr", overrides=sets, workers=1))
    b = xr.open_zarr(run_file(CAMPAIGN, out=tmp_path / "b.zarr", overrides=sets, workers=2))
    for v in ("swarm_angle", "coverage_vs_n", "optimality_gap", "worst_failure_coverage",
              "observed"):
        assert np.array_equal(a[v].values, b[v].values), v
    assert str(a["design_method"].values) == "exact"
    assert str(a["solver_status"].values) == "optimal"
    assert a["coverage_vs_n"].dims == ("n_spacecraft",) and a.sizes["n_spacecraft"] == 6
    assert float(a["best_coverage"]) >= a.attrs["target_coverage"] - 1e-3 - 1e-12
    with pytest.raises(InputError) as ei:
        run_file(CAMPAIGN, out=tmp_path / "c.zarr", overrides=sets + [
            "swarm.min_separation_km=1e5", "run.workers=0"])
    assert ei.value.field == "swarm.min_separation_km"


def test_exact_helix_k1_campaign(tmp_path):
    """Helix candidates, one failure tolerated, through the campaign runner."""
    from ideas_hpc.campaign.run import run_file

    sets = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3",
            "flyby.z_stop_km=3", 'flyby.configuration="helix"', "flyby.helix_rise_km=2.0",
            "design.angle_step_deg=10", "design.n_max=8", "design.failures_tolerated=1",
            "run.workers=0"]
    ds = xr.open_zarr(run_file(CAMPAIGN, out=tmp_path / "h.zarr", overrides=sets))
    assert ds.attrs["configuration"] == "helix" and ds.attrs["failures_tolerated"] == 1
    need = ds.attrs["target_coverage"] - 1e-3
    assert float(ds["worst_failure_coverage"]) >= need - 1e-12
    assert float(ds["best_coverage"]) >= need - 1e-12
    assert ds["worst_failure"].size == 1
    assert float(ds["proven_bound"]) <= ds.sizes["spacecraft"]


@pytest.mark.slow
def test_time_limit_returns_best_so_far_with_gap(eros1708):
    """Strict eros001708, k = 1, a budget spent before the failure programme starts (1 ns):
    a tolerant swarm (greedy completion) with its gap to the proven bound."""
    bank = eros_bank(True, 0.5)
    # n_max 40: the greedy completion needs 21 (the optimum is far fewer)
    res = failure_tolerant(bank, 1, target=min(1.0, bank.reach), eps_tol=EPS, n_max=40,
                           time_limit=1e-9)
    assert res.status == "time_limit" and res.gap > 0.0
    assert res.bound <= res.n and res.gap == pytest.approx((res.n - res.bound) / res.n)
    worst, _, covs, subsets = worst_failure(bank, res.indices, 1)
    expect = subset_coverage(bank.masks, bank.areas,
                             np.array([[j for j in res.indices if j != f[0]] for f in subsets]))
    assert expect.min() >= _need(bank) - 1e-12 and res.worst_failure_coverage == worst


def test_time_limit_without_incumbent_falls_back_to_a_greedy_design():
    # HiGHS can stop at its time limit before it has any swarm (eros022540 in
    # strict mode under load did): the design is then a greedy cover, stated as
    # a time-limited design with its gap to the proven bound, not a traceback.
    from types import SimpleNamespace

    from ideas_hpc.design.exact import _min_result, greedy_cover, greedy_swarm, prepare
    from ideas_hpc.mapping.requirement import threshold_of

    bank = _toy(2)
    need = bank.reach - 0.02
    red, m = prepare(bank, 0.0)
    stopped = SimpleNamespace(x=None, status=1, message="Time limit reached",
                              mip_dual_bound=1.0)
    res = _min_result(bank, red, stopped, 1.0, threshold_of(bank.reach, 0.02), 20, m)
    assert res.status == "time_limit" and res.coverage >= need
    assert res.bound == 1.0 and res.gap == (res.n - 1) / res.n
    assert "greedy" in res.notes[0]
    exact = min_swarm(bank, target=bank.reach, eps_tol=0.02)
    assert res.n >= exact.n  # never better than the optimum
    # separation respected by the greedy cover (2 grid steps), asked for what it can reach
    # with that separation (the need above it cannot: it returns None)
    assert greedy_cover(bank, need, 2, None) is None
    reach_sep = greedy_swarm(bank, 2, None)[1]
    idx = greedy_cover(bank, reach_sep, 2, None)
    assert idx is not None and idx.size >= 3
    assert subset_coverage(bank.masks, bank.areas, idx[None, :])[0] >= reach_sep - 1e-12
    d = np.abs(idx[:, None] - idx[None, :])
    d = np.minimum(d, bank.n_candidates - d)
    assert (d[np.triu_indices(idx.size, 1)] > 2).all()


def test_max_coverage_without_incumbent_gives_the_greedy_swarm_and_its_gap(monkeypatch):
    # On eros022540 HiGHS can reach its time limit before any swarm of N: the
    # curve then holds the greedy swarm, marked time_limit, with a valid bound.
    from types import SimpleNamespace

    import ideas_hpc.design.exact as ex

    bank = _toy(3)
    best = ex.max_coverage(bank, 2)
    monkeypatch.setattr(ex, "solve", lambda *a, **k: (SimpleNamespace(
        x=None, status=1, message="Time limit reached", mip_dual_bound=None), 1.0))
    r = ex.max_coverage(bank, 2)
    assert r.n <= 2 and r.coverage <= best.coverage + 1e-12
    assert r.bound >= best.coverage - 1e-12     # still an upper bound on the optimum
    assert r.status == "time_limit" and r.gap > 0.0        # the greedy pair misses reach


def test_coverage_curve_spends_one_time_budget_and_finishes(monkeypatch):
    # The time limit covers the whole curve: once it is spent, the remaining
    # points are greedy swarms marked time_limit with the union bound, and the
    # curve stays non-decreasing and below its bounds.
    import ideas_hpc.design.coverage_vs_n as cvn

    bank = _toy(4)
    exact = coverage_curve(bank, 6)
    clock = iter(np.arange(0.0, 1000.0, 10.0))   # every call to the clock: 10 s later
    monkeypatch.setattr(cvn.time, "perf_counter", lambda: float(next(clock)))
    r = cvn.coverage_curve(bank, 6, time_limit=5.0)
    assert np.all(np.diff(r.coverage) >= -1e-12)
    assert np.all(r.coverage <= exact.coverage + 1e-12)
    assert np.all(r.bound >= exact.coverage - 1e-12)
    assert set(r.status) <= {"optimal", "time_limit"}
    late = [i for i, s in enumerate(r.status) if s == "time_limit"]
    assert late and all(r.gap[i] > 0 for i in late)      # the budget did bind
    assert all(s == "optimal" for s, c in zip(r.status, r.coverage) if c >= bank.reach - 1e-12)
