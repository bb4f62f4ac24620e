"""The NP GA reaches the certified optimum (issue 13, item 5).

With the paper's budget (population 100, 115 generations) on the real
eros001708, the GA's N must equal the proven fewest spacecraft on the GA's
own angle grid (``design.angle_step_rad`` = 0.01 rad), in paper mode and in
strict mode (exact culling, occlusion, 5 deg elevation). The reference is the
exact designer (HiGHS MILP, status optimal) on the same 628 masks; the GA
never sees it. The GA runs as a user runs it, ``run_file`` on the campaign file with
only the seed changed, so a wiring bug in the campaign path is seen: seed 1 by
default, three more seeds per mode in the slow run (each a whole campaign, ~40-90 s:
the slow run keeps within the CI budget of .ci/run).
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest

from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.design import min_swarm
from ideas_hpc.design.bank import build_bank
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.design.ga.local_search import GridCover

CAMPAIGN = Path(__file__).resolve().parent.parent / "campaigns" / "eros-nadir-ga.toml"
STRICT = ['coverage.mode="exact"', "coverage.occlusion=true", "coverage.min_elevation_deg=5.0"]
EPS = 1e-3
STEP = 0.01
SHIPPED_SEED = 2026   # the campaign file's seed
_CASES: dict = {}


def _case(strict: bool):
    """(bank on the GA's 0.01 rad grid, target, certified optimum N)."""
    if strict not in _CASES:
        c = load(CAMPAIGN, STRICT if strict else [])
        assert c.config.design.angle_step_rad == STEP
        bank = build_bank(setup_from_campaign(c), STEP, snap=False)
        target = 1.0 if bank.reach >= 1.0 - EPS else bank.reach  # as design_nadir does
        ref = min_swarm(bank, target=target, eps_tol=EPS, n_max=20)
        assert ref.status == "optimal" and ref.gap == 0.0
        _CASES[strict] = (bank, target, ref.n)
    return _CASES[strict]


def _campaign_ga(strict: bool, seed: int, root):
    """The GA as a user runs it: ``run_file`` on the campaign file, only the seed changed.
    With the shipped seed in paper mode this is tests/test_campaigns.py's as-shipped run
    on eros001708 (the same overrides): one run of the session serves both."""
    import xarray as xr

    from small_stores import run_once
    from test_campaigns import AS_SHIPPED

    sets = AS_SHIPPED + ([] if seed == SHIPPED_SEED else [f"seed={seed}"]) \
        + (STRICT if strict else [])
    return xr.open_zarr(run_once(CAMPAIGN.name, sets, 0, root))


def _check(strict, seed, tmp_path_factory):
    bank, target, n_opt = _case(strict)
    ds = _campaign_ga(strict, seed, tmp_path_factory.getbasetemp())
    assert int(ds.attrs["campaign_seed"]) == seed
    assert str(ds["design_method"].values) == "ga"
    assert ds.sizes["generation"] == 115 and ds.sizes["individual"] == 100   # paper budget
    n = int(ds["best_swarm_size"])
    assert n == n_opt, f"certified optimum N = {n_opt}; GA seed {seed}: {n}"
    # the stored swarm, re-scored on the reference's masks, reaches the target
    idx = np.rint(np.mod(ds["swarm_angle"].values, 2 * np.pi) / STEP).astype(int)
    assert idx.size == n
    w = bank.areas / bank.areas.sum()
    assert w @ bank.masks[idx].any(axis=0) >= target - EPS - 1e-12


def test_paper_budget_ga_reaches_the_optimum(eros1708, tmp_path_factory):
    """Paper mode, seed 1: the GA before the set-cover local search gave N = 3 (the
    optimum is 2)."""
    _check(False, 1, tmp_path_factory)


# paper mode's third seed is the campaign file's own: that run is the slow as-shipped run
# of tests/test_campaigns.py, flown once for both tests
@pytest.mark.slow
@pytest.mark.parametrize("strict,seed", [(False, s) for s in (0, 2, SHIPPED_SEED)]
                         + [(True, s) for s in range(3)],
                         ids=lambda x: str(x) if not isinstance(x, bool) else
                         ("strict" if x else "paper"))
def test_paper_budget_ga_reaches_the_optimum_more_seeds(eros1708, strict, seed,
                                                        tmp_path_factory):
    _check(strict, seed, tmp_path_factory)


def _brute_min(masks, w, need, n_max):
    for n in range(1, n_max + 1):
        for s in itertools.combinations(range(masks.shape[0]), n):
            if w @ masks[list(s)].any(axis=0) >= need:
                return n
    return None


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_local_search_on_toy_covers(seed):
    """Every improved swarm is feasible with no redundant member; removal and swaps
    never lose feasibility; the separation is respected; a 2-for-1 swap finds the
    exhaustive optimum from a feasible superset of one of its members."""
    rng = np.random.default_rng(seed)
    k, v = 24, 120
    masks = rng.uniform(size=(k, v)) < 0.25
    masks[:, masks.sum(axis=0) == 0] = True
    w = rng.uniform(1, 2, v)
    gc = GridCover(masks, w, STEP, 1.0, EPS, k)
    genomes = np.zeros((30, 1 + k))
    genomes[:, 0] = rng.integers(1, 11, 30)
    genomes[:, 1:] = rng.integers(0, k, (30, k)) * STEP
    wn = w / w.sum()
    for g in gc.improve(genomes):
        s = gc.to_sets(g[None])[0]
        assert wn @ masks[s].any(axis=0) >= 1 - EPS - 1e-12
        for j in range(len(s)):
            assert wn @ masks[s[:j] + s[j + 1:]].any(axis=0) < 1 - EPS - 1e-12
    # greedy seeds from random starts keep the separation (2 grid steps)
    gs = GridCover(masks, w, STEP, 1.0, EPS, k, min_sep_steps=2)
    for g in gs.seed_population(genomes, 0.5, rng)[:15]:
        s = gs.to_sets(g[None])[0]
        d = np.abs(np.subtract.outer(s, s))
        assert np.all(np.minimum(d, k - d)[np.triu_indices(len(s), 1)] >= 2)
    # no removal helps {a, b, x} (b and x each see half of the right side), a 2-for-1
    # swap does: drop b and x, add c (sees the whole right side) -> {a, c}
    m = np.zeros((6, 8), dtype=bool)
    m[0, :4] = True                    # a: left half
    m[1, 4:6] = True                   # b
    m[2, 6:] = True                    # x
    m[3, 4:] = True                    # c
    m[4, [0, 4]] = m[5, [1, 7]] = True  # decoys
    gc = GridCover(m, np.ones(8), STEP, 1.0, EPS, 5)
    g = np.array([[3, 0.0, STEP, 2 * STEP, 0.0, 0.0]])
    assert gc.remove([0, 1, 2]) == [0, 1, 2]
    assert sorted(gc.to_sets(gc.improve(g))[0]) == [0, 3]
    assert _brute_min(m, np.full(8, 1 / 8), 1 - EPS, 4) == 2


def test_campaign_ga_with_min_separation(eros1708, tmp_path):
    """The campaign GA with the local search keeps ``swarm.min_separation_km`` and still
    meets the certified optimum (which also respects it) on its grid."""
    import xarray as xr

    from ideas_hpc.campaign.run import run_file
    from ideas_hpc.flyby.swarm_geometry import min_separation_angle

    sets = [f"design.angle_step_rad={2 * np.pi / 40!r}", "design.population=20",
            "design.generations=10", "design.n_max=6", "run.workers=0",
            "swarm.min_separation_km=40"]
    ds = xr.open_zarr(run_file(CAMPAIGN, out=tmp_path / "np.zarr", overrides=sets))
    c = load(CAMPAIGN, sets)
    sep = min_separation_angle(40.0, setup_from_campaign(c).d_sep_m)
    a = np.sort(np.asarray(ds["swarm_angle"].values, dtype=float))
    d = np.diff(np.r_[a, a[0] + 2 * np.pi])
    assert a.size == 1 or np.all(d >= sep - 1e-9)
    assert float(ds["optimality_gap"]) == 0.0
    assert int(ds["best_swarm_size"]) == float(ds["proven_bound"])
