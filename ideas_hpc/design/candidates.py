"""Per-candidate rows for the designers: what one spacecraft at one swarm angle sees or maps.

A design key is ``(theta rad, period s (0 = nadir), ic key)``. All candidates
of a call are targeted in one compiled call, flown (ideal, or simulated: on the
reference of the geometry flown, or with ``attitude_start = "paper"`` from
``initial_conditions(seed, ic_key, 1)``) and imaged (usable images only); the designers then score
any swarm as a union of rows (paper eq. 26), the GA through
:class:`~ideas_hpc.design.ga.swarm_eval.MaskBank` and the exact designer through
:class:`~ideas_hpc.design.bank.CandidateBank`.

With a ``[coverage]`` requirement (issue 14) a row is what the spacecraft
*maps* on its own (:func:`ideas_hpc.mapping.coverage.quality_per_spacecraft`): a
usable observation and, with ``require_stereo``, a stereo pair from its own
track. That union is exact for every per-image limit and a lower bound of
the swarm's stereo coverage (a pair can come from two spacecraft).
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.attitude import initial_conditions
from ideas_hpc.flyby.flight import FlybySetup, target, undrawn_perturbation
from ideas_hpc.flyby.views import FlightPlan, flight_views
from ideas_hpc.mapping.coverage import observed_per_spacecraft, quality_per_spacecraft, stereo_pair_table


def _views(setup: FlybySetup, keys):
    th = np.array([k[0] for k in keys], dtype=np.float64)
    per = np.array([k[1] for k in keys], dtype=np.float64)
    tgt = target(setup, th)
    periods = per if setup.maneuver.sweeps else None

    def random_state():     # each candidate's own sample: initial_conditions(seed, ic key, 1)
        draws = [initial_conditions(setup.seed, int(k[2]), 1) for k in keys]
        return tuple(np.ascontiguousarray(np.concatenate([d[j] for d in draws]))
                     for j in range(3))

    v = flight_views(setup, th, periods, None, None,
                     undrawn_perturbation(setup, th.size, random_state),
                     plan=FlightPlan(series=False, trajectory=(tgt.position_T, tgt.velocity_T)))
    return v.r_img_T, v.imaging_BT, setup.world.sun_at_images(setup)


def candidate_masks(setup: FlybySetup, keys) -> np.ndarray:
    """(K, V) bool rows of the designers: seen, or mapped when a requirement is set."""
    return rows_from_views(setup, *_views(setup, keys))


def rows_from_views(setup: FlybySetup, r_img, dcm, sun) -> np.ndarray:
    """(K, V) bool rows (seen, or mapped with a requirement) of flown candidates:
    positions ``r_img`` (K, n_img, 3) m and camera ``dcm`` (K, n_img, 3, 3) at the
    image times, ``sun`` (n_img, 3) or None."""
    if setup.coverage.requirement:
        return quality_per_spacecraft(setup.body.shape, r_img, dcm, setup.image_times,
                                      setup.eta_rad, setup.near_m, setup.far_m,
                                      options=setup.coverage, sun_T=sun)["mapped"]
    return observed_per_spacecraft(setup.body.shape, r_img, dcm, setup.eta_rad, setup.near_m,
                                   setup.far_m, options=setup.coverage, sun_T=sun)


def candidate_quality(setup: FlybySetup, keys, pairs: bool = False) -> dict:
    """Per-candidate ``usable``, ``stereo``, ``mapped`` ((K, V) bool) and ``resolution`` (m);
    with ``pairs`` also the stereo table of every candidate pair, ``pairs``
    ((K (K - 1) / 2, V) bool), from the same flights."""
    r_img, dcm, sun = _views(setup, keys)
    args = (setup.body.shape, r_img, dcm, setup.image_times, setup.eta_rad, setup.near_m, setup.far_m)
    out = quality_per_spacecraft(*args, options=setup.coverage, sun_T=sun)
    if pairs:
        out["pairs"] = stereo_pair_table(*args, options=setup.coverage, sun_T=sun)
    return out
