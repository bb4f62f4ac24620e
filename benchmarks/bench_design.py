"""Benchmark: the certified exact NP design against the paper-budget GA, on eros001708.

Everything in this process, masks included in every time (a fresh candidate
bank per measurement, compiled kernels warmed up first):

* exact NP design on the 0.5 deg grid (720 candidates), paper and strict mode
  (exact culling, occlusion, 5 deg elevation);
* the k = 1 failure-tolerant design (paper and strict) and the
  coverage-versus-N curve (N <= 8, paper mode);
* the paper-budget NP GA (population 100, 115 generations, pygad) on the same
  problem: the same 0.5 deg candidate masks, target and eps_tol.

Last line: ``design: <R>x faster than the paper-budget GA (<S> s, certified optimum)``
with ``S`` the exact paper-mode design time.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numpy as np  # noqa: E402

from ideas_hpc.campaign.schema.campaign_tables import load  # noqa: E402
from ideas_hpc.design import (build_bank, coverage_curve, failure_tolerant,  # noqa: E402
                              min_swarm)
from ideas_hpc.design.candidates import candidate_masks  # noqa: E402
from ideas_hpc.campaign.setup import setup_from_campaign  # noqa: E402
from ideas_hpc.design.ga.genetic import run_nadir_ga  # noqa: E402
from ideas_hpc.design.ga.swarm_eval import nadir_keys  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = ROOT / "campaigns" / "eros-nadir.toml"
STRICT = ['coverage.mode="exact"', "coverage.occlusion=true", "coverage.min_elevation_deg=5.0"]
STEP = np.deg2rad(0.5)
EPS = 1e-3
SEP = 1e3


def _setup(strict: bool):
    setup = setup_from_campaign(load(CAMPAIGN, STRICT if strict else []))
    candidate_masks(setup, [(0.1, 0.0, 0), (0.2, 0.0, 1)])  # compile
    return setup


def _exact(setup):
    t = time.perf_counter()
    bank = build_bank(setup, STEP)
    res = min_swarm(bank, target=min(1.0, bank.reach), eps_tol=EPS, n_max=20,
                    min_separation=SEP)
    return time.perf_counter() - t, res, bank


def main() -> None:
    setups = {m: _setup(m == "strict") for m in ("paper", "strict")}
    times = {}
    for mode, setup in setups.items():
        dt, res, bank = _exact(setup)
        times[mode] = dt
        print(f"exact {mode:6s}: {dt:5.1f} s (masks included), N = {res.n} {res.status} "
              f"(gap {res.gap:g}), coverage {100 * res.coverage:.3f} %, angles "
              f"{np.round(np.degrees(res.theta), 1).tolist()} deg")
    for mode, setup in setups.items():
        t = time.perf_counter()
        bank = build_bank(setup, STEP)
        k1 = failure_tolerant(bank, 1, target=min(1.0, bank.reach), eps_tol=EPS, n_max=20,
                              min_separation=SEP, time_limit=120)
        t_k1 = time.perf_counter() - t
        print(f"k = 1 {mode:6s}: {t_k1:5.1f} s (masks included), N = {k1.n} {k1.status} (proven "
              f"bound {k1.bound:g}), worst single failure "
              f"{100 * k1.worst_failure_coverage:.3f} %")
    setup = setups["paper"]
    t = time.perf_counter()
    bank = build_bank(setup, STEP)
    curve = coverage_curve(bank, 8, min_separation=SEP)
    t_curve = time.perf_counter() - t
    print(f"curve N<=8  : {t_curve:5.1f} s (masks included), coverage "
          f"{np.round(100 * curve.coverage, 3).tolist()} %, all {set(curve.status)}")

    t = time.perf_counter()
    bank = build_bank(setup, STEP, snap=False)
    target = min(1.0, bank.reach)
    idx = {round(th / STEP): i for i, th in enumerate(bank.theta)}

    def evaluate(genomes):
        swarms = [[idx[k[2] % bank.n_candidates] for k in nadir_keys(g, STEP)] for g in genomes]
        return bank.coverage(swarms), np.rint(genomes[:, 0]).astype(int)

    ga = run_nadir_ga(evaluate, n_max=20, population=100, generations=115, seed=2026,
                      eps_tol=EPS, angle_step=STEP, target=target,
                      min_separation=SEP / setup.d_sep_m)
    t_ga = time.perf_counter() - t
    n_opt = _exact(setup)[1].n
    print(f"GA paper    : {t_ga:5.1f} s (masks included), {ga.evaluations} designs, N = "
          f"{ga.best_swarm_size} (certified optimum {n_opt}: gap "
          f"{100 * (ga.best_swarm_size - n_opt) / ga.best_swarm_size:.0f} %)")
    print(f"design: {t_ga / times['paper']:.1f}x faster than the paper-budget GA "
          f"({times['paper']:.1f} s, certified optimum)")


if __name__ == "__main__":
    main()
