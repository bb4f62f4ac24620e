"""Recipe: a new requirement rule is one registration, from this test module alone (issue 40).

A toy target rule ("nine-tenths": the target is 90 % of what the candidates reach together)
is registered here; every designer receives it only as the
:class:`~ideas_hpc.mapping.requirement.Threshold` that
:meth:`~ideas_hpc.mapping.requirement.Requirement.threshold` resolves, and the campaign file
picks it by name (``design.target_rule``). Oracles: enumeration of every swarm, with the
threshold computed here from the rule's definition, not by the code under test.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from design_oracle import min_tolerant_size, subset_coverage
from ideas_hpc.design import CandidateBank
from ideas_hpc.design.api import (CoverSettings, NadirGAProblem, NadirGASettings,
                                  ReliableSettings, ScenarioProblem, GASearch, minimize)
from ideas_hpc.design.ga.local_search import GridCover
from ideas_hpc.design.ga.swarm_eval import snap_angle
from ideas_hpc.design.stereo import StereoBank
from ideas_hpc.core.mapping.stereo_pairs import pair_index
from ideas_hpc.mapping import requirement as req

ROOT = Path(__file__).resolve().parents[1]
EPS = 0.02
SHARE = 0.9


def _nine_tenths(reach, eps_tol):
    return SHARE * (1.0 if reach is None else reach)


@pytest.fixture
def toy_rule():
    """The rule registered for one test, and taken out of the registry after it."""
    from ideas_hpc.campaign.schema import design_table   # the schema is built first

    req.register_rule(req.TargetRule("nine-tenths", _nine_tenths, "90 % of the reach"))
    assert "nine-tenths" in design_table.DESIGN["target_rule"].choices     # read live
    yield req.Requirement(eps_tol=EPS, rule="nine-tenths")
    del req.TARGET_RULES["nine-tenths"]


def _bank(seed=3, k=10, v=60, p=0.4) -> CandidateBank:
    rng = np.random.default_rng(seed)
    step = 2 * np.pi / k
    return CandidateBank(theta=step * np.arange(k), masks=rng.uniform(size=(k, v)) < p,
                         areas=rng.uniform(1, 3, v), step_rad=step, d_sep_m=1e4)


def _fewest(cover_of, k: int, need: float, n_top: int) -> int:
    """Fewest members of any swarm of ``k`` candidates whose ``cover_of`` meets ``need``."""
    for n in range(1, n_top + 1):
        if any(cover_of(s) >= need - 1e-12 for s in itertools.combinations(range(k), n)):
            return n
    raise AssertionError("no swarm meets the need")


def _oracle_reach(bank) -> float:
    return float(subset_coverage(bank.masks, bank.areas, np.arange(bank.n_candidates)[None, :])[0])


def _oracle_need(bank) -> float:
    return SHARE * _oracle_reach(bank) - EPS


def test_the_exact_designer_meets_the_toy_rule_and_the_default_rule_differs(toy_rule):
    bank = _bank()
    need = _oracle_need(bank)
    thr = toy_rule.threshold(bank.reach)
    assert thr.need == pytest.approx(need, abs=1e-15)

    def cov(s):
        return subset_coverage(bank.masks, bank.areas, np.array([s]))[0]

    n_toy = _fewest(cov, bank.n_candidates, need, 6)
    # the rule decides N here: the default rule (100 %, or the reach when 100 % - eps_tol
    # is out of it) needs more
    reach = _oracle_reach(bank)
    n_default = _fewest(cov, bank.n_candidates, (1.0 if reach >= 1.0 - EPS else reach) - EPS,
                        bank.n_candidates)
    assert n_toy < n_default
    res = minimize(bank, CoverSettings(threshold=thr, n_max=6))
    assert res.designer == "exact" and res.status == "optimal"
    assert res.n == n_toy and cov(tuple(res.indices)) >= need - 1e-12


def test_the_failure_tolerant_designer_meets_the_toy_rule(toy_rule):
    bank = _bank(seed=5, k=9, p=0.45)
    need = _oracle_need(bank)
    n_true, _ = min_tolerant_size(bank.masks, bank.areas, need, 1, 8)
    res = minimize(bank, CoverSettings(threshold=toy_rule.threshold(bank.reach), n_max=8,
                                       failures_tolerated=1))
    assert res.designer == "failure-tolerant" and res.n == n_true


def _stereo(seed=1, k=12, v=60) -> StereoBank:
    rng = np.random.default_rng(seed)
    own = rng.random((k, v)) < 0.03
    pairs = np.zeros((k * (k - 1) // 2, v), dtype=bool)
    for a, b in itertools.combinations(range(k), 2):
        if 2 <= min(b - a, k - (b - a)) <= 5:
            pairs[pair_index(a, b, k)] = rng.random(v) < 0.25
    bank = CandidateBank(theta=np.arange(k) * 2 * np.pi / k, masks=own,
                         areas=rng.uniform(0.5, 2.0, v), step_rad=2 * np.pi / k, d_sep_m=1e5)
    return StereoBank(bank, pairs)


def test_the_stereo_designer_meets_the_toy_rule(toy_rule):
    sb = _stereo()
    k = sb.bank.n_candidates

    def mapped(s):      # own tracks and every pair of members, counted directly
        m = sb.bank.masks[list(s)].any(axis=0)
        for a, b in itertools.combinations(sorted(s), 2):
            m |= sb.pairs[pair_index(a, b, k)]
        return float(sb.bank.areas[m].sum() / sb.bank.areas.sum())

    need = SHARE * mapped(range(k)) - EPS
    res = minimize(sb, CoverSettings(threshold=toy_rule.threshold(sb.reach), n_max=k))
    assert res.designer == "stereo" and res.n == _fewest(mapped, k, need, k)


def test_the_success_probability_designer_meets_the_toy_rule(toy_rule):
    rng = np.random.default_rng(7)
    s_n, c_n, v_n, p_f, p = 3, 8, 20, 0.1, 0.8
    rows = np.zeros((s_n, c_n, v_n), dtype=bool)
    for s, c in itertools.product(range(s_n), range(c_n)):
        lo = (v_n * c) // c_n + rng.integers(-1, 2)
        rows[s, c, np.arange(lo, lo + 4 + rng.integers(0, 3)) % v_n] = True
    areas = rng.uniform(0.5, 1.5, v_n)
    w = areas / areas.sum()
    reach = float(w[rows.any(axis=(0, 1))].sum())   # what every candidate sees somewhere
    need = SHARE * reach - EPS

    def probability(swarm):          # failures enumerated, unions taken directly
        total = 0.0
        for s in range(s_n):
            for alive in itertools.product((False, True), repeat=len(swarm)):
                members = [c for c, a in zip(swarm, alive) if a]
                cov = w[rows[s, members].any(axis=0)].sum() if members else 0.0
                if cov >= need - 1e-12:
                    total += (1 - p_f) ** sum(alive) * p_f ** (len(swarm) - sum(alive))
        return total / s_n

    n_true = next(n for n in range(1, c_n + 1)
                  if any(probability(sw) >= p - 1e-12
                         for sw in itertools.combinations(range(c_n), n)))
    res = minimize(ScenarioProblem(rows, areas, np.arange(c_n) * 2 * np.pi / c_n),
                   ReliableSettings(p=p, p_f=p_f, threshold=toy_rule.threshold(reach),
                                    n_max=c_n))
    assert res.designer == "success-probability" and res.n == n_true
    assert probability(tuple(res.indices)) >= p - 1e-12


def test_the_ga_and_its_local_search_meet_the_toy_rule(toy_rule):
    bank = _bank(seed=11, k=12)
    need = _oracle_need(bank)
    thr = toy_rule.threshold(bank.reach)
    cover = GridCover(bank.masks, bank.areas, bank.step_rad, n_max=8, threshold=thr)

    def cov(s):
        return subset_coverage(bank.masks, bank.areas, np.array([s]))[0]

    def members(genome):
        return np.unique([snap_angle(a, bank.step_rad)[1]
                          for a in genome[1:1 + int(round(genome[0]))]])

    def evaluate(genomes):
        return bank.coverage([members(g) for g in genomes]), np.rint(genomes[:, 0]).astype(int)

    res = minimize(NadirGAProblem(evaluate, cover), NadirGASettings(
        search=GASearch(population=12, generations=8, seed=4), n_max=8,
        eps_tol=thr.eps_tol, angle_step_rad=bank.step_rad, target=thr.target))
    idx = np.unique([snap_angle(a, bank.step_rad)[1] for a in res.swarm_rad])
    assert cov(tuple(idx)) >= need - 1e-12          # feasible under the toy rule
    assert res.n == idx.size >= _fewest(cov, bank.n_candidates, need, 8)


def test_a_campaign_picks_the_rule_by_name(toy_rule, tmp_path):
    """``design.target_rule`` reads the registry live: the campaign's threshold is the toy
    rule's, and its N the fewest by enumeration on the same candidate bank."""
    from ideas_hpc.campaign.run import run_file
    from ideas_hpc.campaign.schema.campaign_tables import load
    from ideas_hpc.campaign.setup import setup_from_campaign
    from ideas_hpc.design import build_bank

    sets = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3",
            "flyby.z_stop_km=3", "design.angle_step_deg=10", "design.verify_samples=0",
            "run.workers=0", "dynamics.srp=false", f"design.eps_tol_pct={100 * EPS}",
            'design.target_rule="nine-tenths"']
    campaign = ROOT / "campaigns" / "eros-design-nominal.toml"
    ds = xr.open_zarr(run_file(campaign, out=tmp_path / "d.zarr", overrides=sets))
    bank = build_bank(setup_from_campaign(load(campaign, sets)), np.deg2rad(10.0))
    need = _oracle_need(bank)
    assert ds.attrs["threshold_coverage"] == pytest.approx(need, abs=1e-12)

    def cov(s):
        return subset_coverage(bank.masks, bank.areas, np.array([s]))[0]

    assert int(ds["best_swarm_size"]) == _fewest(cov, bank.n_candidates, need, 4)


def test_an_unknown_rule_names_the_key():
    from ideas_hpc.base.errors import InputError
    from ideas_hpc.campaign.schema.campaign_tables import load

    with pytest.raises(InputError) as ei:
        load(ROOT / "campaigns" / "eros-design-nominal.toml", ['design.target_rule="most"'])
    assert ei.value.field == "design.target_rule" and "reach" in ei.value.message
