"""Verify a designed swarm by Monte Carlo: how often does it still reach the target?

A design is chosen on the nominal model. :func:`verify_swarm` flies the chosen
swarm through the campaign's ``[monte_carlo]`` dispersions (attitude, gravity,
SRP, initial state errors, failures, camera misalignment), sample ``k`` with
the same seed streams as a ``monte-carlo`` campaign
(:mod:`ideas_hpc.montecarlo.dispersions`), and returns the coverage
distribution and ``P(coverage >= threshold)``. A ``monte-carlo`` campaign with
the same seed, swarm and ``[monte_carlo]`` table reproduces any sample.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass

import numpy as np

from ideas_hpc.flyby.flight import FlybySetup, Perturbation
from ideas_hpc.mapping.requirement import meets
from ideas_hpc.base.progress import map_chunks, plural
from ideas_hpc.montecarlo.dispersions import draw_sample
from ideas_hpc.montecarlo.sample import Nominal, design_nominal, fly_sample


@dataclass(frozen=True)
class Verification:
    """Monte Carlo verification of one swarm."""

    coverage: np.ndarray     # (M,) area fraction per sample
    n_failed: np.ndarray     # (M,) failed spacecraft per sample
    threshold: float         # coverage a sample must reach (target - eps_tol)
    wall_s: float

    @property
    def probability(self) -> float:
        """Fraction of samples that meet the threshold
        (:func:`~ideas_hpc.mapping.requirement.meets`: the designers' comparison)."""
        return float(np.mean(meets(self.coverage, self.threshold))) if self.coverage.size else \
            float("nan")

    def summary(self) -> str:
        """The run's line (:func:`verification_line`, with the time it took)."""
        return verification_line(self.coverage, self.n_failed, self.threshold,
                                 self.probability, wall_s=self.wall_s)


def verification_line(coverage, n_failed, threshold: float, probability: float, *,
                      who: str = "", wall_s: float | None = None) -> str:
    """The Monte Carlo verification in one line, worded here only (the run prints it with
    ``wall_s``, the report with ``who``, the swarm it is about).

    ``coverage`` (M,) area fractions, ``n_failed`` (M,) failed spacecraft per sample,
    ``threshold`` and ``probability`` fractions.
    """
    c = 100 * np.asarray(coverage, dtype=np.float64)
    failed = int((np.asarray(n_failed) > 0).sum())
    return (f"Monte Carlo verification{' ' + who if who else ''}: P(coverage >= threshold "
            f"{100 * threshold:.2f} %) = {100 * probability:.1f} % over "
            f"{plural(c.size, 'dispersed sample')} (min {c.min():.2f} %, 5th percentile "
            f"{np.percentile(c, 5):.2f} %, median {np.median(c):.2f} %; "
            f"{plural(failed, 'sample')} with a failed spacecraft)"
            + ("" if wall_s is None else f" in {wall_s:.1f} s"))


def _samples(ks, *, setup: FlybySetup, nominal: Nominal, mc, seed: int):
    out = []
    for k in ks:
        values, pert = draw_sample(mc, seed, k, nominal.theta, setup)
        # only the coverage is kept: no per-vertex image counts (same coverage)
        r = fly_sample(setup, nominal, Perturbation(**pert), counts=False)
        out.append((float(r["coverage"]), int(values["n_failed"])))
    return out


def verify_swarm(setup: FlybySetup, theta, periods, *, mc, seed: int, n_samples: int,
                 threshold: float, client=None, chunk_size: int = 8) -> Verification:
    """Fly ``n_samples`` dispersed copies of the swarm ``theta`` (rad).

    Parameters
    ----------
    setup : FlybySetup
    theta : (N,) rad
    periods : (N,) s or None
        Sweep periods (FoV sweeping).
    mc : MonteCarlo
        The validated ``[monte_carlo]`` table (:class:`~ideas_hpc.campaign.schema.campaign_tables.MonteCarlo`, SI).
    seed : int
        Campaign seed; sample ``k`` draws from ``SeedSequence(seed, spawn_key=(k,))``.
    n_samples : int
    threshold : float
        Coverage (0..1) a sample must reach to count as a success.
    client : distributed.Client, optional
        Spread the samples over its workers in chunks of ``chunk_size``
        (the numbers do not depend on it).
    """
    t0 = time.perf_counter()
    nom = design_nominal(setup, theta, periods)
    kw = dict(setup=setup, nominal=nom.for_tasks(), mc=mc, seed=seed)
    ks = list(range(int(n_samples)))
    parts = [ks[i:i + chunk_size] for i in range(0, len(ks), chunk_size)]
    rows = [r for part in map_chunks(functools.partial(_samples, **kw), parts, client,
                                     desc="verification") for r in part]
    cov = np.array([r[0] for r in rows], dtype=np.float64)
    failed = np.array([r[1] for r in rows], dtype=np.int32)
    return Verification(cov, failed, float(threshold), time.perf_counter() - t0)
