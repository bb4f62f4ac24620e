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
from ideas_hpc.attitude.run_settings import InitialState
from ideas_hpc.flyby.flight import FlybySetup, target
from ideas_hpc.flyby.camera import camera_dcms, imaging_dcms
from ideas_hpc.mapping.coverage import observed_per_spacecraft, quality_per_spacecraft, stereo_pair_table


def _views(setup: FlybySetup, keys):
    th = np.array([k[0] for k in keys], dtype=np.float64)
    per = np.array([k[1] for k in keys], dtype=np.float64)
    tgt = target(setup, th)
    r_img = np.ascontiguousarray(tgt.position_T[:, ::setup.image_every])
    periods = per if setup.maneuver.sweeps else None
    if setup.attitude_mode == "simulated":
        if setup.attitude_start == "paper":
            draws = [initial_conditions(setup.seed, int(k[2]), 1) for k in keys]
            s0, w0, W0 = (np.ascontiguousarray(np.concatenate([d[j] for d in draws]))
                          for j in range(3))
        else:       # the nominal flight: exactly on the reference (SPEC 7d)
            s0, w0, W0 = (np.zeros((th.size, 3)) for _ in range(3))
        dcm, att = camera_dcms(setup.with_(decimate=max(1, int(round((setup.tf_s - setup.t0_s)
                                                                      / setup.dt_s)))),
                               th, periods, state0=InitialState(s0, w0, W0),
                               track_T=(tgt.position_T, tgt.velocity_T),
                               start="absolute" if setup.attitude_start == "paper"
                               else "reference")
        dcm = imaging_dcms(setup, dcm, att, r_img)
    else:
        dcm, _ = camera_dcms(setup, th, periods, r_img_T=r_img)
    sun = setup.sun_T() if setup.coverage.needs_sun else None
    return r_img, dcm, sun


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
