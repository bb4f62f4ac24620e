"""The flight ``ideas-hpc export`` writes, read from a store of any kind that holds one swarm.

What each store kind gives (its registry capabilities,
:mod:`ideas_hpc.campaign.schema.kinds`; never its name):

* one flown swarm (``one_swarm``: a flyby, or a design's chosen swarm): the swarm is the
  store's ``swarm_angle`` (with ``sweep_period`` when it sweeps), flown again at full
  resolution from the store's resolved config (:func:`~ideas_hpc.flyby.flight.fly`, the
  nominal flight the campaign stored). When the store holds the trajectory
  (``position``) the re-flown one must match it within :data:`REPRODUCE_TOL_M`
  (otherwise another code version wrote the store); when it holds none, the flight is
  flown from the resolved config alone and :attr:`ExportFlight.notes` says so;
* dispersed samples (``samples``: a Monte Carlo store): by default its nominal flight
  (the designed swarm on the nominal model, whose trajectory is the store's
  ``position``); ``sample=K`` flies sample K through its own draws
  (:func:`~ideas_hpc.montecarlo.dispersions.draw_sample`,
  :func:`~ideas_hpc.flyby.flight.fly_open_loop`, as the campaign did), and its
  coverage must equal the stored ``coverage[K]``;
* anything else (a Pareto front of many swarms) is refused in one line naming the kind.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ideas_hpc.base.errors import InputError

#: Largest distance between the re-flown and the stored trajectory, m.
REPRODUCE_TOL_M = 1e-3
#: Largest difference between a re-flown sample's coverage and the stored one.
REPRODUCE_COVERAGE = 1e-12


@dataclass
class ExportFlight:
    """One swarm's flight as the export needs it (SI, frame T, flyby time)."""

    c: object                       # the validated campaign of the store's resolved config
    setup: object                   # its FlybySetup
    times_s: np.ndarray             # (T,) trajectory steps
    position_T: np.ndarray          # (N, T, 3) m
    velocity_T: np.ndarray          # (N, T, 3) m/s, relative to the rotating frame T
    image_times_s: np.ndarray       # (n_img,)
    r_img_T: np.ndarray             # (N, n_img, 3) m
    dcm_BT: np.ndarray              # (N, n_img, 3, 3) camera frame (misalignment applied)
    attitude: object | None         # AttitudeResult (simulated) or None
    active: np.ndarray | None       # (N,) bool, False: failed in this sample
    what: str = ""                  # one line: which flight this is
    theta: np.ndarray | None = None     # (N,) rad, the swarm angles flown
    periods: np.ndarray | None = None   # (N,) s, sweep periods (None: no sweep)
    #: (N, 3, 3) ``[C B]``: the camera misalignment of a dispersed sample (None: aligned)
    dcm_CB: np.ndarray | None = None
    #: (N, T, 3) m: the nominal trajectory (what a store's ``position`` holds) when this
    #: flight is a dispersed sample; None: this flight is the nominal one
    nominal_position_T: np.ndarray | None = None
    notes: list = field(default_factory=list)
    #: (N, n_img, 3, 3) the cameras the coverage saw (unusable images blinded); None: unknown
    imaging_BT: np.ndarray | None = None


def _campaign(attrs: dict):
    from ideas_hpc.campaign.schema.campaign_tables import validate_campaign
    from ideas_hpc.campaign.schema.toml_file import CampaignSource

    cfg = dict(attrs["config"])
    cfg.pop("models", None)
    src = Path(attrs["campaign_file"]) if attrs.get("campaign_file") else None
    return validate_campaign(CampaignSource(data=cfg, path=src, resolved=True))


def store_kind(attrs: dict):
    """The registered kind of a store, or an InputError naming ``store``."""
    from ideas_hpc.campaign.schema.kinds import kind_of

    try:
        return kind_of(str(attrs.get("kind")))
    except ValueError as exc:
        raise InputError(str(exc), field="store") from None


def flight_of(store, attrs: dict, sample: int | None = None) -> ExportFlight:
    """The flight to export from ``store`` (module docstring)."""
    import xarray as xr

    from ideas_hpc.campaign.setup import setup_from_campaign

    kind = store_kind(attrs)
    if not kind.one_swarm:
        raise InputError(f"a {kind.name} store cannot be exported: it holds no single flown "
                         f"swarm ({kind.doc})", field="store")
    if sample is not None and not kind.samples:
        raise InputError(f"a {kind.name} store holds one flight and no dispersed samples; "
                         "leave the option out", field="--sample")
    with xr.open_zarr(store) as ds:
        if "swarm_angle" not in ds:
            raise InputError(f"a {kind.name} store without swarm_angle: no swarm to export",
                             field="store")
        theta = np.asarray(ds["swarm_angle"].values, dtype=np.float64)
        periods = (np.asarray(ds["sweep_period"].values, dtype=np.float64)
                   if "sweep_period" in ds else None)
        stored = np.asarray(ds["position"].values) if "position" in ds else None
        n_samples = int(ds.sizes.get("sample", 0))
        cov_k = None
        if sample is not None:
            if not 0 <= sample < n_samples:
                raise InputError(f"sample {sample} is out of range: the store holds "
                                 f"{n_samples} samples, 0 to {n_samples - 1}",
                                 field="--sample")
            cov_k = float(ds["coverage"].values[sample])
    c = _campaign(attrs)
    setup = setup_from_campaign(c, maneuver=kind.maneuver)
    if sample is None:
        out = _nominal(c, setup, theta, periods, kind.name)
    else:
        out = _sample(c, setup, theta, periods, sample, cov_k, kind.name)
    out.theta, out.periods = theta, periods
    _check_trajectory(out, stored, setup.decimate)
    return out


def _nominal(c, setup, theta, periods, kind_name: str) -> ExportFlight:
    from ideas_hpc.flyby.flight import fly

    res = fly(setup, theta, periods)
    tg = res.targeting
    return ExportFlight(c, setup, tg.times, tg.position_T, tg.velocity_T, res.image_times,
                        res.r_img_T, res.dcm_BT, res.attitude, None,
                        what=f"the nominal flight of the {kind_name} store's "
                             f"{theta.size}-spacecraft swarm", imaging_BT=res.imaging_BT)


def _sample(c, setup, theta, periods, k: int, stored_coverage: float, kind_name: str) -> ExportFlight:
    from ideas_hpc.flyby.camera import misalignment_dcms
    from ideas_hpc.flyby.flight import Perturbation, fly_open_loop
    from ideas_hpc.montecarlo.dispersions import draw_sample
    from ideas_hpc.montecarlo.sample import design_nominal

    if not np.isfinite(stored_coverage):
        raise InputError(f"sample {k} is not finished in this store (resume the campaign "
                         "first)", field="--sample")
    nom = design_nominal(setup, theta, periods)
    _, pert = draw_sample(c.config.monte_carlo, c.config.seed, k, nom.theta, setup)
    p = Perturbation(**pert)
    f = fly_open_loop(setup, nom.theta, nom.periods, nom.r0_T, nom.v0_T, p)
    gap = abs(f.coverage.coverage - stored_coverage)
    if not gap <= REPRODUCE_COVERAGE:
        raise InputError(f"re-flying sample {k} gives coverage {f.coverage.coverage!r}, the "
                         f"store holds {stored_coverage!r} (another code version?); re-run "
                         "the campaign first", field="store")
    mis = None if p.misalignment_prv is None else misalignment_dcms(p.misalignment_prv)
    return ExportFlight(c, setup, nom.times, f.position_T, f.velocity_T, f.image_times,
                       f.r_img_T, f.dcm_BT, f.attitude,
                       None if p.active is None else np.asarray(p.active, dtype=bool),
                       dcm_CB=mis, what=f"sample {k} of the {kind_name} store (its dispersions drawn "
                            "again from the store's seed)", nominal_position_T=nom.position_T,
                       imaging_BT=f.imaging_BT)


def omega_BN_B(fl: ExportFlight) -> np.ndarray | None:
    """(N, n_img, 3) the flown inertial rate of each spacecraft at the images, B
    components (rad/s): the simulated attitude's, or the reference's under perfect
    tracking on the ring (:func:`ideas_hpc.attitude.ideal_omega_BN_B`); None where the
    reference is not a function of time (an encounter's or body tracking)."""
    att = fl.attitude
    if att is not None and getattr(att, "image_omega", None) is not None:
        return np.asarray(att.image_omega[0], dtype=np.float64)
    s = fl.setup
    if att is not None or not s.geometry.analytic_reference_rate or s.maneuver.tracks_body:
        return None
    from ideas_hpc.attitude import ideal_omega_BN_B

    return ideal_omega_BN_B(fl.theta, s.body.params.spin_rate, fl.image_times_s - s.t0_s,
                            mode=s.maneuver.name, periods=fl.periods,
                            theta_max=s.theta_max_rad, p_min=s.p_min_s)


def camera_rates_J(fl: ExportFlight, dcm_CJ) -> np.ndarray | None:
    """(N, n_img, 3) the flown inertial angular velocity of each camera at the images in
    J2000 components (rad/s), from :func:`omega_BN_B`: ``omega_J = [C J]^T [C B]
    omega_B`` (the camera is fixed in B, so its rate is B's); None when that is None (the
    CK then takes its rates from the attitudes)."""
    w_b = omega_BN_B(fl)
    if w_b is None:
        return None
    w_c = w_b if fl.dcm_CB is None else np.einsum("kab,kib->kia", fl.dcm_CB, w_b)
    return np.einsum("kiab,kia->kib", dcm_CJ, w_c)


def _check_trajectory(out: ExportFlight, stored, decimate: int) -> None:
    """Refuse a re-flown nominal trajectory more than 1 mm from the stored one; note a store
    without one."""
    if stored is None:
        out.notes.append("the store holds no trajectories: flew the swarm's nominal flight "
                         "from the store's resolved config")
        return
    nominal = out.position_T if out.nominal_position_T is None else out.nominal_position_T
    flown = nominal[:, ::decimate]
    gap = float(np.max(np.abs(stored - flown))) if stored.shape == flown.shape else np.inf
    if not gap <= REPRODUCE_TOL_M:
        raise InputError(f"re-flying the store's config gives a trajectory {gap:.3g} m away from "
                         "the stored one (another code version?); re-run the campaign first",
                         field="store")
