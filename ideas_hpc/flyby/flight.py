"""One flyby simulation: sizing -> targeting -> attitude -> coverage (SPEC sections 2-6).

Orchestration only: every step is a compiled kernel behind its boundary
module (:mod:`ideas_hpc.flyby.sizing`, :mod:`ideas_hpc.dynamics.trajectory`,
:mod:`ideas_hpc.attitude`, :mod:`ideas_hpc.mapping.coverage`). Two attitude options:

``ideal``
    perfect tracking: the camera frame is the reference frame at every image
    (fast, deterministic);
``simulated``
    closed-loop reaction-wheel attitude with the sliding-mode controller, from
    seeded random initial conditions (SPEC section 5).

Geometry choices (SPEC section 3): the ring swarm flies at radius ``d_sep`` in
the body's xy-plane from ``z_start`` to ``z_stop``. The helical configuration
raises each spacecraft's start and stop by ``helix_rise * theta_i / (2 pi)``;
its ring frame keeps z horizontal toward the spin axis (``[TS] = I``), so each
spacecraft's pointing depends on its own angle only and swarms stay unions of
independent spacecraft (which the GA relies on).
"""

from __future__ import annotations

import dataclasses
import hashlib
import sys
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from ideas_hpc.attitude import Gains, Maneuver, SpacecraftModel, campaign_maneuver, initial_conditions
from ideas_hpc.attitude.modes import AttitudeMode, AttitudeStart, attitude_mode, attitude_start, \
    undrawn_start
from ideas_hpc.body.bodies import Body
from ideas_hpc.flyby.encounter import Encounter
from ideas_hpc.flyby.geometry import Geometry, geometry_of
from ideas_hpc.flyby.navigation import NavigationPlan
from ideas_hpc.base.errors import InputError
from ideas_hpc.flyby.views import FlightPlan, flight_views
from ideas_hpc.flyby.world import World
from ideas_hpc.mapping.coverage import CoverageResult, compute_coverage
from ideas_hpc.mapping.options import CoverageOptions
from ideas_hpc.flyby.sizing import Sizing
from ideas_hpc.flyby.usable import ImageUse
from ideas_hpc.dynamics.force_model import ForceModel
from ideas_hpc.dynamics.trajectory import TargetingError, TargetingResult


@dataclass(frozen=True)
class FlybySetup:
    """Everything a flyby needs, resolved to SI once (picklable, sent to workers).

    Names carry their unit (``_s``, ``_m``, ``_rad``): times ``t0_s``, ``tf_s``
    (flyby window, from the epoch of the elements plus ``epoch_s``), integration
    and image steps ``dt_s``, ``image_dt_s``; ring radius ``d_sep_m``, paper track
    ends ``z_start_m``, ``z_stop_m`` (helix: ``helix_rise_m`` more start per full turn);
    camera half angle ``eta_rad``, near and far planes ``near_m``, ``far_m``;
    sweep amplitude ``theta_max_rad``; targeting tolerance ``tol_m``; shortest
    sweep period ``p_min_s``; arrival epoch ``epoch_s``.
    """

    body: Body
    sizing: Sizing
    t0_s: float
    tf_s: float
    dt_s: float
    image_dt_s: float
    d_sep_m: float
    z_start_m: float
    z_stop_m: float
    configuration: str
    helix_rise_m: float
    eta_rad: float
    near_m: float
    far_m: float
    theta_max_rad: float
    maneuver: Maneuver
    attitude_mode: str
    decimate: int
    tol_m: float
    max_iter: int
    seed: int
    force_model: ForceModel = field(default_factory=ForceModel)
    spacecraft: SpacecraftModel | None = None
    gains: Gains | None = None
    coverage: CoverageOptions = field(default_factory=CoverageOptions)
    p_min_s: float = 18.0
    epoch_s: float = 0.0
    encounter: Encounter | None = None   # None: the paper's geometry (ideas_hpc.flyby.encounter)
    #: Disturbance torques on every spacecraft (ideas_hpc.attitude.torque_terms);
    #: read by the simulated attitude only.
    torques: tuple = ()
    imaging: ImageUse | None = None      # None: every image counts (ideas_hpc.flyby.usable)
    # where a flight without explicit initial conditions starts its closed loop:
    # "paper" (random, seeded by ``seed`` and the sample), else on the reference (SPEC 7d)
    attitude_start: str = "paper"
    #: where the closed-loop flights run, "cpu" or "cuda" (ideas_hpc.attitude.device): an
    #: execution choice, left out of the bank's shaping hash
    device: str = "cpu"
    #: The target prior whose worlds the scenarios fly (a
    #: :class:`~ideas_hpc.body.target_prior.TargetPrior`, :mod:`ideas_hpc.flyby.target_world`);
    #: None: every scenario flies ``body`` (the known target)
    target: object | None = None
    #: navigation errors of an encounter and terminal tracking (SPEC 7f;
    #: ideas_hpc.flyby.navigation.NavigationPlan), drawn by the dispersions; None: none
    navigation: NavigationPlan | None = None

    @property
    def geometry(self) -> Geometry:
        """The geometry flown (:mod:`ideas_hpc.flyby.geometry`): the paper's, or the
        encounter's when ``encounter`` is set."""
        return geometry_of(self.encounter)

    @property
    def image_every(self) -> int:
        return int(round(self.image_dt_s / self.dt_s))

    @property
    def image_times(self) -> np.ndarray:
        n = int(round((self.tf_s - self.t0_s) / self.image_dt_s))
        return self.t0_s + self.image_dt_s * np.arange(n + 1)

    @property
    def world(self) -> World:
        """The nominal world this setup flies (:class:`~ideas_hpc.flyby.world.World`): its
        body, force model, arrival epoch and encounter."""
        return World(self.body, self.force_model, self.epoch_s, self.encounter)

    @property
    def attitude(self) -> AttitudeMode:
        """The registry entry of ``attitude_mode`` (:mod:`ideas_hpc.attitude.modes`)."""
        return attitude_mode(self.attitude_mode)

    @property
    def start(self) -> AttitudeStart:
        """The registry entry of ``attitude_start`` (:mod:`ideas_hpc.attitude.modes`)."""
        return attitude_start(self.attitude_start)

    @cached_property
    def flight_key(self) -> str:
        """A digest of everything but the world (body, force model, epoch, encounter):
        the key of the per-world statics this setup prepares
        (:func:`ideas_hpc.flyby.world.cached_static`)."""
        # every float exactly (arrays of the spacecraft, the gains): two setups that differ
        # anywhere never share a key
        with np.printoptions(floatmode="unique", threshold=sys.maxsize):
            own = [(f.name, repr(getattr(self, f.name))) for f in dataclasses.fields(self)
                   if f.name not in _WORLD_FIELDS]
        return hashlib.sha1(repr(own).encode()).hexdigest()

    def sun_T(self, times=None, epoch=None) -> np.ndarray:
        """Unit body -> Sun directions (n, 3) in T at flyby ``times`` (default: the
        image times), from the ephemeris at ``epoch + times`` (arrival epoch, s)."""
        t = self.image_times if times is None else np.asarray(times, dtype=np.float64)
        w = self.world if epoch is None else replace(self.world, epoch_s=float(epoch))
        return w.sun_T(t)

    def with_(self, **kw) -> "FlybySetup":
        if isinstance(kw.get("maneuver"), str):      # a campaign name
            kw["maneuver"] = campaign_maneuver(kw["maneuver"])
        return replace(self, **kw)


#: The fields of :class:`FlybySetup` that make its :class:`~ideas_hpc.flyby.world.World`.
_WORLD_FIELDS = ("body", "force_model", "epoch_s", "encounter", "target")


def endpoints(setup: FlybySetup, theta) -> tuple[np.ndarray, np.ndarray]:
    """Start and target positions (N, 3) in T for swarm angles ``theta`` (rad); on an
    encounter the start and the ring point at closest approach."""
    return setup.geometry.endpoints(setup, np.asarray(theta, dtype=np.float64).ravel())


def target(setup: FlybySetup, theta, *, raise_on_failure: bool = True) -> TargetingResult:
    """Target the swarm ``theta`` (rad) from its start to its arrival point.

    A failure the user can fix becomes an :class:`~ideas_hpc.base.errors.InputError`
    naming the setup parameter to change (:func:`targeting_input_error`; the
    campaign layer maps it to the file's key, :data:`ideas_hpc.campaign.schema.model_fields.FLYBY_FIELDS`).
    """
    th = np.asarray(theta, dtype=np.float64).ravel()
    try:
        return setup.geometry.target(setup, th, raise_on_failure=raise_on_failure)
    except TargetingError as exc:
        raise targeting_input_error(exc, setup, th) from None
    except InputError as exc:
        if exc.field not in ("r0_T", "r_target_T"):
            raise
        raise InputError(f"{exc.message}: the flyby starts or ends too close to the body; "
                         "move `z_start_m` / `z_stop_m` further out",
                         field="z_start_m" if exc.field == "r0_T" else "z_stop_m") from None


def targeting_input_error(exc: TargetingError, setup: FlybySetup, theta) -> InputError:
    """One line for a failed targeting: the worst spacecraft, its miss, the parameter to change.

    The cause is read off the failed spacecraft's last trajectory and miss history:

    * it came within ``R_max`` of the body's centre (or the integrator gave up):
      the flyby is too close, ``d_sep_m``;
    * it used every iteration but the miss stopped shrinking over the last
      three (Newton converges quadratically until integration noise): the
      tolerance is tighter than the integration allows, ``tol_m``;
    * otherwise it ran out of iterations, ``max_iter``.

    The error names the :class:`FlybySetup` parameter (field, and between
    backticks in the message); the campaign layer maps it to the file's key.
    """
    res = exc.result
    failed = np.asarray(exc.failed, dtype=int)
    fm = res.final_miss
    worst = int(failed[np.argmax(np.where(np.isfinite(fm[failed]), fm[failed], np.inf))])
    n = int(res.n_iter[worst])
    hist = res.miss[worst, :n + 1]
    dist = np.linalg.norm(res.position_T[worst], axis=1)
    dist = dist[np.isfinite(dist)]     # an integration that broke off leaves NaN behind
    closest = float(dist.min()) if dist.size else float("nan")
    r_max = setup.body.shape.r_max
    others = f" (and {failed.size - 1} more)" if failed.size > 1 else ""
    head = (f"targeting did not converge for spacecraft {worst}{others} at swarm angle "
            f"{theta[worst]:.4g} rad: miss {fm[worst]:.3g} m after {n} iterations, tolerance "
            f"{setup.tol_m:g} m; ")
    if closest <= r_max or not np.all(np.isfinite(hist)) or n < setup.max_iter:
        where = (f"its path comes within {closest / 1e3:.3g} km of the body's centre"
                 if np.isfinite(closest) else "its integration broke off near the body")
        return InputError(head + f"{where} (R_max {r_max / 1e3:.3g} km): increase `d_sep_m` "
                          f"(now {setup.d_sep_m / 1e3:.4g} km)", field="d_sep_m")
    if n >= 4 and np.min(hist[-3:]) >= 0.5 * np.min(hist[:-3]):
        return InputError(head + f"the miss stalls near {np.min(hist):.3g} m: loosen "
                          "`tol_m`", field="tol_m")
    return InputError(head + f"raise `max_iter` (now {setup.max_iter})", field="max_iter")


@dataclass(frozen=True)
class Perturbation:
    """How one flyby departs from the nominal one (SI, frame T); None: nominal.

    The Monte Carlo dispersions (:mod:`ideas_hpc.montecarlo.dispersions`) are
    turned into one of these per sample and flown by :func:`fly_open_loop`.
    """

    ics: tuple | None = None                  # (sigma0, omega0, wheel0), each (N, 3)
    # (sigma_BR0, omega_BR0_B, wheel0): a start relative to the reference flown (SPEC 7d);
    # replaces ``ics``
    ics_reference: tuple | None = None
    acquisition_s: float = 0.0                # closed loop from ``ics`` before the window, s
    # the scenario's world parameters (World.perturbed; any of
    # dynamics.force_model.world_parameters: mu, c20, c22, reflectivity, pole_ra, ...)
    params_override: dict | None = None
    position_error_T: np.ndarray | None = None  # (N, 3) m
    velocity_error_T: np.ndarray | None = None  # (N, 3) m/s
    active: np.ndarray | None = None          # (N,) bool, False: failed
    misalignment_prv: np.ndarray | None = None  # (N, 3) rad, camera [CB] as a PRV
    # navigation (SPEC 7f; ideas_hpc.flyby.nav_flight), frame N of the encounter, m: the
    # true target's offset from the predicted one at the predicted TCA (3,), common to
    # the swarm, and each member's own error (N, 3)
    target_offset_N: np.ndarray | None = None
    member_offset_N: np.ndarray | None = None
    centroid_prv: np.ndarray | None = None      # (N, 3) rad: terminal tracking's error


@dataclass
class FlybyOutcome:
    """What one flyby produced (arrays in SI, frame T)."""

    theta: np.ndarray
    periods: np.ndarray | None
    targeting: TargetingResult | None
    image_times: np.ndarray
    r_img_T: np.ndarray                 # (N, n_img, 3)
    dcm_BT: np.ndarray                  # (N, n_img, 3, 3) camera frame at images
    coverage: CoverageResult
    attitude: object | None = None      # AttitudeResult for 'simulated'
    extras: dict = field(default_factory=dict)
    position_T: np.ndarray | None = None  # (N, T, 3) m, the flown trajectory (open loop)
    velocity_T: np.ndarray | None = None  # (N, T, 3) m/s, its velocities (open loop)
    #: (N, n_img, 3, 3) the cameras the coverage saw: ``dcm_BT`` with the unusable images
    #: blinded (:func:`ideas_hpc.flyby.camera.imaging_dcms`, perfect tracking's alike)
    imaging_BT: np.ndarray | None = None


def fly(setup: FlybySetup, theta, periods=None, *, sample: int = 0, ics=None,
        counts: bool = True, raise_on_failure: bool = True) -> FlybyOutcome:
    """Target a swarm on the nominal model, fly it and compute what it imaged.

    A perturbed flyby of a designed swarm is :func:`fly_open_loop`.

    Parameters
    ----------
    theta : (N,) rad
        Swarm angles.
    periods : (N,) s, optional
        Sweep periods (FoV sweeping).
    sample : int
        Sample index whose seeded initial attitude is used (a closed loop whose
        ``setup.start`` has ``nominal_random``; otherwise the loop starts on the reference).
    ics : tuple of (N, 3) arrays, optional
        Explicit ``(sigma0, omega0, wheel0)``.
    counts : bool
        Also count images per vertex (``times_seen``).
    """
    th = np.asarray(theta, dtype=np.float64).ravel()
    if th.size == 0:
        raise InputError("needs at least one spacecraft", field="theta")
    tgt = target(setup, th, raise_on_failure=raise_on_failure)
    pert = Perturbation(ics=ics) if ics is not None else undrawn_perturbation(
        setup, th.size, lambda: initial_conditions(setup.seed, sample, th.size))
    v = flight_views(setup, th, periods, None, None, pert,
                     plan=FlightPlan(trajectory=(tgt.position_T, tgt.velocity_T)))
    return FlybyOutcome(theta=th, periods=None if periods is None else np.asarray(periods),
                        targeting=tgt, image_times=setup.image_times, r_img_T=v.r_img_T,
                        dcm_BT=v.dcm_BT, coverage=_coverage(setup, setup.world, v, None, counts),
                        attitude=v.attitude, imaging_BT=v.imaging_BT)


def undrawn_perturbation(setup: FlybySetup, n: int, random_state) -> "Perturbation":
    """The :class:`Perturbation` of a flight of ``n`` spacecraft without drawn errors:
    nothing, and for a closed loop the setup's own start
    (:func:`ideas_hpc.attitude.modes.undrawn_start`; ``random_state()`` returns the
    seeded random state of the flight's samples)."""
    if not setup.attitude.closed_loop:
        return Perturbation()
    state, word = undrawn_start(setup.attitude_start, n, random_state)
    return Perturbation(ics_reference=state) if word == "reference" else Perturbation(ics=state)


def fly_open_loop(setup: FlybySetup, theta, periods, r0_T, v0_T,
                  perturbation: Perturbation = Perturbation(), *,
                  counts: bool = True) -> FlybyOutcome:
    """Fly a designed swarm open loop (no retargeting) through a perturbed world.

    The Monte Carlo sample: the start states ``r0_T``, ``v0_T`` (N, 3; m, m/s)
    targeted on the nominal model, plus the perturbation's state errors, are
    propagated through its world (:class:`~ideas_hpc.flyby.world.World`: gravity,
    SRP, pole, Sun), its attitude initial conditions
    are flown, its camera misalignments applied and its failed spacecraft left
    out of the coverage. ``counts=False`` skips the per-vertex image counts
    (``times_seen`` is then 0/1; the coverage and first-seen times are the same).
    """
    th = np.asarray(theta, dtype=np.float64).ravel()
    world = setup.world.perturbed(perturbation.params_override)
    v = flight_views(setup, th, periods, r0_T, v0_T, perturbation, world=world)
    cov = _coverage(setup, world, v, perturbation.active, counts)
    return FlybyOutcome(theta=th, periods=None if periods is None else np.asarray(periods),
                        targeting=None, image_times=setup.image_times, r_img_T=v.r_img_T,
                        dcm_BT=v.dcm_BT, coverage=cov, attitude=v.attitude,
                        position_T=v.position_T, velocity_T=v.velocity_T,
                        imaging_BT=v.imaging_BT)


def open_loop_views(setup: FlybySetup, theta, periods, r0_T, v0_T,
                    perturbation: Perturbation = Perturbation(), *, ideal_dcm_BT=None):
    """What :func:`fly_open_loop` images from: positions ``r_img_T`` (N, n_img, 3) m and
    camera DCMs (N, n_img, 3, 3) at the image times (misalignment applied), the
    attitude result (simulated) and the trajectory (N, T, 3) m. Failures are not applied;
    unusable images are blinded (:func:`ideas_hpc.flyby.camera.imaging_dcms`).
    ``ideal_dcm_BT``: no longer read (perfect tracking's cameras are kept per world by
    :func:`ideas_hpc.flyby.views.flight_views`); accepted for older callers."""
    v = flight_views(setup, theta, periods, r0_T, v0_T, perturbation)
    return v.r_img_T, v.imaging_BT, v.attitude, v.position_T


def _coverage(setup: FlybySetup, world: World, views, active, counts):
    flown = world.flown(setup)
    return compute_coverage(flown.body.shape, views.r_img_T, views.imaging_BT,
                            setup.image_times, setup.eta_rad, setup.near_m, setup.far_m,
                            options=setup.coverage, sun_T=world.sun_at_images(setup),
                            active=active, counts=counts)
