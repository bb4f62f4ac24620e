"""Multi-objective design (issue 14 item 5): objectives, non-dominated filter, NSGA-II
against the proven coverage-versus-N curve on eros001708, the design-pareto kind."""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.cli import main
from ideas_hpc.design import CandidateBank, build_bank, coverage_curve, worst_failure
from ideas_hpc.design.pareto.nsga2 import (check_objectives, evaluate, members_of, minimised,
                                     non_dominated, repair, run_pareto, swap_ascent)
from ideas_hpc.base.errors import InputError
from ideas_hpc.campaign.setup import setup_from_campaign
from design_oracle import pair_coverage
from campaign_copies import fitted
from test_design_exact import eros_bank   # same flyby geometry; shares its bank cache

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = ROOT / "campaigns" / "eros-pareto.toml"


def _union(bank, idx) -> float:
    """Area fraction seen by the candidates ``idx`` (plain NumPy over the bank's masks)."""
    seen = np.zeros(bank.masks.shape[1], dtype=bool)
    for j in np.asarray(idx, dtype=int):
        seen |= bank.masks[j]
    return float(bank.areas[seen].sum() / bank.areas.sum())


def _dominated_brute(f):
    out = np.zeros(len(f), dtype=bool)
    for i, j in itertools.permutations(range(len(f)), 2):
        if all(f[j] <= f[i]) and any(f[j] < f[i]):
            out[i] = True
    return ~out


@pytest.mark.parametrize("seed", range(5))
def test_non_dominated_against_brute_force(seed):
    rng = np.random.default_rng(seed)
    m = 2 + seed % 3
    # integer values: many ties and repeated points, which the filter must keep
    f = rng.integers(0, 6, size=(60, m)).astype(float)
    assert np.array_equal(non_dominated(f), _dominated_brute(f))
    g = rng.normal(size=(80, m))
    assert np.array_equal(non_dominated(g), _dominated_brute(g))


@dataclass
class QualityBank(CandidateBank):
    """A bank with the optional quality arrays of issue 14."""

    stereo: np.ndarray = None
    resolution: np.ndarray = None


def _hand_bank(quality=True):
    inf = np.inf
    masks = np.array([[1, 1, 0, 0], [0, 1, 1, 0], [0, 0, 0, 1]], dtype=bool)
    kw = dict(theta=np.arange(3) * 2 * np.pi / 3, masks=masks,
              areas=np.array([1.0, 2.0, 3.0, 4.0]), step_rad=2 * np.pi / 3, d_sep_m=1e4)
    if not quality:
        return CandidateBank(**kw)
    return QualityBank(**kw, stereo=np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 0]], bool),
                       resolution=np.array([[1.0, 4.0, inf, inf], [inf, 2.0, 3.0, inf],
                                            [inf, inf, inf, 5.0]]))


def test_objectives_hand_computed():
    bank = _hand_bank()
    names = ("n", "coverage", "worst_failure_coverage", "stereo_coverage", "mean_resolution")
    members = np.array([[0, 1, -1], [2, -1, -1], [0, 2, -1], [0, 1, 2]])
    v = evaluate(bank, names, members)
    expect = np.array([
        [2, 6 / 10, 3 / 10, 3 / 10, (1 * 1 + 2 * 2 + 3 * 3) / 6],
        [1, 4 / 10, 0.0, 0.0, 5.0],
        [2, 7 / 10, 3 / 10, 1 / 10, (1 * 1 + 2 * 4 + 4 * 5) / 7],
        [3, 1.0, 6 / 10, 3 / 10, (1 + 4 + 9 + 20) / 10],
    ])
    np.testing.assert_allclose(v, expect, rtol=0, atol=1e-15)
    # minimised: n and resolution as they are, the coverages negated
    np.testing.assert_array_equal(minimised(names, v)[:, :2], np.c_[v[:, 0], -v[:, 1]])
    # a swarm that maps no vertex has no resolution
    nothing = QualityBank(**{**_hand_bank().__dict__, "masks": np.zeros((3, 4), bool)})
    assert evaluate(nothing, ("mean_resolution",), [[0, -1, -1]])[0, 0] == np.inf


def test_optional_objectives_need_the_quality_arrays():
    bank = _hand_bank(quality=False)
    for name in ("stereo_coverage", "mean_resolution"):
        with pytest.raises(InputError, match=name) as ei:
            evaluate(bank, ("n", name), [[0, 1, -1]])
        assert ei.value.field == "objectives"
    with pytest.raises(InputError) as ei:
        run_pareto(bank, ("n", "stereo_coverage"), n_max=2, population=4, generations=1, seed=0)
    assert ei.value.field == "objectives"


@pytest.mark.parametrize("names, msg", [
    (["n"], "at least two"), (["n", "coverage", "n"], "more than once"),
    (["n", "covrage"], "unknown"), ("coverage", "list"), ([1, 2], "list")])
def test_check_objectives_refuses(names, msg):
    with pytest.raises(InputError, match=msg) as ei:
        check_objectives(names)
    assert ei.value.field == "objectives"


def _toy(seed=1, k=24, v=120, p=0.25):
    rng = np.random.default_rng(seed)
    step = 2 * np.pi / k
    return CandidateBank(theta=step * np.arange(k), masks=rng.uniform(size=(k, v)) < p,
                         areas=rng.uniform(1, 3, v), step_rad=step, d_sep_m=1e4)


def test_worst_failure_objective_equals_enumeration():
    bank = _toy(2)
    rng = np.random.default_rng(5)
    members = np.full((30, 6), -1)
    swarms = []
    for i in range(30):
        s = rng.choice(bank.n_candidates, size=rng.integers(1, 7), replace=False)
        members[i, :s.size] = s
        swarms.append(s)
    got = evaluate(bank, ("worst_failure_coverage",), members)[:, 0]
    for g, s in zip(got, swarms):
        assert g == worst_failure(bank, s, 1)[0]


@pytest.mark.parametrize("m", [0, 1, 3])
def test_repair_gives_distinct_separated_swarms(m):
    rng = np.random.default_rng(m)
    k, n_max = 20, 5
    g = np.c_[rng.integers(0, 8, 200), rng.integers(-3, 25, (200, n_max))]
    r = repair(g, k, m)
    for row in members_of(r):
        s = np.sort(row[row >= 0])
        assert 1 <= s.size <= n_max and np.all((s >= 0) & (s < k))
        if s.size > 1:
            d = np.diff(np.r_[s, s[0] + k])
            assert d.min() > m
    assert np.array_equal(repair(r, k, m), r)        # a repaired genome is left alone


def test_swap_ascent_never_lowers_coverage_and_is_a_local_optimum():
    bank = _toy(3)
    rng = np.random.default_rng(0)
    for _ in range(10):
        s = rng.choice(bank.n_candidates, 3, replace=False)
        t = swap_ascent(bank, s, 0)
        c = bank.coverage([t])[0]
        assert c >= bank.coverage([s])[0] and t.size == 3
        swaps = [np.r_[np.delete(t, i), j] for i in range(3) for j in range(bank.n_candidates)
                 if j not in t]
        assert np.max(bank.coverage(swaps)) <= c + 1e-15


@pytest.mark.parametrize("seed", [1, 2])
def test_toy_front_against_exhaustive_search(seed):
    """Three objectives on a toy bank: every front point is non-dominated among all
    swarms of up to 3 candidates, and the (n, coverage) front is the exhaustive one."""
    bank = _toy(seed, k=12, v=60, p=0.3)
    all_sets = [np.array(c) for n in range(1, 4) for c in itertools.combinations(range(12), n)]
    members = np.full((len(all_sets), 3), -1)
    for i, s in enumerate(all_sets):
        members[i, :s.size] = s
    names = ("n", "coverage", "worst_failure_coverage")
    every = minimised(names, evaluate(bank, names, members))
    res = run_pareto(bank, names, n_max=3, population=30, generations=15, seed=seed)
    front = minimised(names, res.values)
    for f in front:   # no swarm of the whole space dominates a front point
        assert not np.any(np.all(every <= f, axis=1) & np.any(every < f, axis=1))
    best = {n: max(bank.coverage([s])[0] for s in all_sets if s.size == n) for n in (1, 2, 3)}
    two = run_pareto(bank, ("n", "coverage"), n_max=3, population=20, generations=10, seed=seed)
    for n, c in zip(two.n, two.values[:, 1]):
        assert c == pytest.approx(best[n], abs=1e-12)


def _check_front_against_curve(bank, n_max, seeds, population=40, generations=15):
    curve = coverage_curve(bank, n_max, min_separation=1e3)
    for seed in seeds:
        res = run_pareto(bank, ("n", "coverage"), n_max=n_max, population=population,
                         generations=generations, seed=seed, min_separation=1e3)
        n, cov = res.values[:, 0].astype(int), res.values[:, 1]
        assert np.all(np.diff(n) > 0) and np.all(np.diff(cov) > 0)     # a front, sorted
        for k, c in zip(n, cov):
            assert curve.status[k - 1] == "optimal"
            assert abs(c - curve.coverage[k - 1]) <= 1e-12, (seed, k, c, curve.coverage)
        # the front reaches the best coverage of any swarm, with the fewest spacecraft
        top = int(np.argmax(curve.coverage >= curve.coverage[-1] - 1e-12)) + 1
        assert n[-1] == top and list(n) == list(range(1, top + 1))


def test_paper_front_matches_exact_curve(eros1708):
    """Paper mode, 0.5 deg grid: the NSGA-II front is the proven curve for several seeds."""
    _check_front_against_curve(eros_bank(False, 0.5), 6, seeds=(0, 1, 2))


@pytest.mark.slow
def test_strict_front_matches_exact_curve(eros1708):
    """Strict mode (occlusion, 5 deg elevation): three points on the front, all proven."""
    _check_front_against_curve(eros_bank(True, 0.5), 8, seeds=(0, 1, 2, 3))


def test_cli_end_to_end(eros1708, tmp_path):
    """``ideas-hpc run campaigns/eros-pareto.toml`` writes a store xarray opens; report works."""
    out = tmp_path / "p.zarr"
    assert main(["run", str(CAMPAIGN), "--out", str(out), "--no-progress",
                 "--workers", "0"]) == 0
    ds = xr.open_zarr(out)
    assert ds.attrs["kind"] == "design-pareto"
    for v in ("pareto_n", "pareto_coverage", "pareto_swarm", "pareto_gap_to_exact",
              "coverage_vs_n"):
        assert v in ds
    assert ds["pareto_swarm"].attrs["units"] == "rad"
    n = ds["pareto_n"].values
    sw = ds["pareto_swarm"].values
    assert np.array_equal(np.isfinite(sw).sum(axis=1), n)
    # the stored swarms reproduce their stored coverage from freshly computed masks
    bank = eros_bank(False, 1.0)
    idx = [np.rint(r[np.isfinite(r)] / bank.step_rad).astype(int) for r in sw]
    cov = ds["pareto_coverage"].values
    np.testing.assert_allclose([_union(bank, i) for i in idx], cov, atol=1e-15)
    # the gap to the exact curve, computed here by enumeration: singles and all pairs
    # (the 1 km separation excludes no pair of this 1 deg grid, 2.7 km apart), and for
    # larger swarms the union of every candidate (an upper bound any swarm meets)
    pairs = pair_coverage(bank.masks, bank.areas)
    best = {1: float(np.diag(pairs).max()), 2: float(pairs[np.triu_indices_from(pairs, 1)].max())}
    reach = _union(bank, np.arange(bank.n_candidates))
    gap = []
    for k, c in zip(n, cov):
        if k in best:
            gap.append(best[k] - c)
        else:
            assert c >= reach - 1e-12, (k, c, reach)     # proven by the union bound
            gap.append(0.0)
    np.testing.assert_allclose(ds["pareto_gap_to_exact"].values, gap, atol=1e-12)
    np.testing.assert_allclose(gap, 0.0, atol=1e-12)
    assert ds.attrs["pareto_matches_exact"] == 1
    assert main(["report", str(out), "--out", str(tmp_path / "rep")]) == 0
    text = (tmp_path / "rep" / "summary.txt").read_text()
    assert "Pareto front (n, coverage)" in text
    assert (tmp_path / "rep" / "design_pareto_front.png").stat().st_size > 0


def test_three_objectives_through_run_file_on_the_ellipsoid(tmp_path):
    """The kind on the built-in ellipsoid (no data): a stored front of three objectives
    whose rows are mutually non-dominated and whose values the stored swarms reproduce."""
    from ideas_hpc.campaign.run import run_file

    names = ["n", "coverage", "worst_failure_coverage"]
    sets = ['body.name="ellipsoid"', "design.angle_step_deg=5.0",
            f"design.objectives={names!r}".replace("'", '"')]
    # without the shipped time_limit_s: it bounds the exact (n, coverage) curve only
    out = run_file(fitted("eros-pareto.toml", sets), out=tmp_path / "e.zarr", workers=0,
                   overrides=sets)
    ds = xr.open_zarr(out)
    assert "coverage_vs_n" not in ds and "pareto_gap_to_exact" not in ds
    vals = np.c_[[ds[f"pareto_{x}"].values for x in names]].T
    assert vals.shape[0] >= 2 and non_dominated(minimised(names, vals)).all()
    setup = setup_from_campaign(load(CAMPAIGN, ['body.name="ellipsoid"']))
    bank = build_bank(setup, np.deg2rad(5.0))
    sw = ds["pareto_swarm"].values
    members = np.full(sw.shape, -1)
    for i, r in enumerate(sw):
        idx = np.rint(r[np.isfinite(r)] / bank.step_rad).astype(int)
        members[i, :idx.size] = idx
    # re-scored here with plain NumPy over the bank's masks (not the objectives' evaluator)
    for m, row in zip(members, vals):
        s = m[m >= 0]
        worst = min((_union(bank, np.delete(s, j)) for j in range(s.size)), default=0.0) \
            if s.size > 1 else 0.0
        np.testing.assert_allclose(row, [s.size, _union(bank, s), worst], rtol=0, atol=1e-12)
