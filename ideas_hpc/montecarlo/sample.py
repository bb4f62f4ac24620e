"""One Monte Carlo sample: the designed nominal swarm flown through a perturbed world."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ideas_hpc.flyby.camera import discarded_images
from ideas_hpc.flyby.flight import FlybySetup, Perturbation, endpoints, fly_open_loop, target
from ideas_hpc.mapping.coverage import quality_arrays


@dataclass(frozen=True)
class Nominal:
    """The designed swarm: angles, periods and the nominal targeted trajectory."""

    theta: np.ndarray
    periods: np.ndarray | None
    r0_T: np.ndarray
    v0_T: np.ndarray
    times: np.ndarray
    position_T: np.ndarray
    velocity_T: np.ndarray
    miss: np.ndarray

    def for_tasks(self) -> "Nominal":
        """What a chunk task needs (start states and arrival points): the sampled
        trajectory stays on the client instead of being shipped with every task."""
        return Nominal(self.theta, self.periods, self.r0_T, self.v0_T, self.times[-1:],
                       np.ascontiguousarray(self.position_T[:, -1:]),
                       np.ascontiguousarray(self.velocity_T[:, -1:]), self.miss)


def design_nominal(setup: FlybySetup, theta, periods) -> Nominal:
    th = np.asarray(theta, dtype=float)
    r0, _ = endpoints(setup, th)
    tg = target(setup, th)
    return Nominal(th, None if periods is None else np.asarray(periods, float), r0, tg.v0_T,
                   tg.times, tg.position_T, tg.velocity_T, tg.miss)


def fly_sample(setup: FlybySetup, nom: Nominal, pert: Perturbation, *,
               counts: bool = True) -> dict:
    """One Monte Carlo sample: the flyby pipeline with the sample's perturbation.

    ``counts=False`` when ``times_seen`` is not stored (the verification): the
    coverage kernel then stops each vertex's scan at its first sighting, and
    every other output is unchanged (``times_seen`` is 0/1).
    """
    f = fly_open_loop(setup, nom.theta, nom.periods, nom.r0_T, nom.v0_T, pert, counts=counts)
    cov = f.coverage
    out = {"coverage": cov.coverage, "coverage_count": cov.coverage_count,
           "coverage_seen": cov.coverage_seen, **quality_arrays(cov),
           "observed": cov.observed, "first_seen": cov.first_seen,
           "times_seen": cov.times_seen, "arrival_error": np.linalg.norm(
               f.position_T[:, -1] - nom.position_T[:, -1], axis=1)}
    if f.attitude is not None:
        for name in ("sigma_error", "omega_error", "wheel_speed", "wheel_torque"):
            out[name] = getattr(f.attitude, name)[0]
        found = discarded_images(setup, f.attitude)
        if found is not None:
            out["images_discarded_smear"], out["images_discarded_settle"] = found
    return out
