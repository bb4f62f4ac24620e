"""Fast exact scenario rows: the nominal flight once, then only what a deviation can change.

Boundary of :mod:`ideas_hpc.core.mapping.scenario_rows`. :class:`RowEngine` flies the
candidates once on the nominal model with ideal attitude, records each
(candidate, vertex)'s first seeing image and whether any camera within a
deviation *budget* could see it, and then turns any perturbed flight
(positions and camera DCMs at the images) into rows identical to
:func:`ideas_hpc.design.candidates.rows_from_views` on that flight. The budget only
decides speed, never the rows; it is taken from a pilot scenario (the
deviations of scenario 0, with head room). Rows with a ``[coverage]``
requirement (quality masks) take no proofs, and neither does a scenario whose world
differs from the nominal one in what the rows read besides the flight (its shape, or
its Sun under a lighting requirement: :meth:`~ideas_hpc.flyby.world.World.mapping_key`):
those come from the world's own statics, built once per world and shared by every
candidate (:func:`world_rows`, the world bank of issue 43: each row stops at its first
usable image), identical to the full recomputation :func:`full_rows_of`. Every scenario is flown by the one
flight path (:func:`ideas_hpc.flyby.views.flight_views`), which picks the one-pass
closed loop (the pipeline's flight, same bits) when it covers the scenario.
"""

from __future__ import annotations

import threading
import uuid
from dataclasses import dataclass, field

import numpy as np

from ideas_hpc.attitude.modes import perfect_tracking
from ideas_hpc.design.candidates import rows_from_views
from ideas_hpc.core.mapping import scenario_rows as _k
from ideas_hpc.core.mapping.coverage import first_image_by_spacecraft
from ideas_hpc.core.mapping.scenario_proofs import BC_ANY, windows, witness_proofs
from ideas_hpc.flyby.flight import FlybySetup, Perturbation
from ideas_hpc.flyby.views import FlightPlan, flight_views
from ideas_hpc.flyby.world import World, cached_static
from ideas_hpc.core.mapping.records import Nominal
from ideas_hpc.mapping.coverage import camera_record, check_geometry
from ideas_hpc.mapping.world_rows import WorldStatics, rows_of_world, world_statics

#: Head room on the pilot's deviations (speed only).
HEADROOM = 1.5
#: Per process: engine token -> its nominal flight, that flight's kernel records and
#: the engine's flight buffers per thread (RowEngine._cached); what a flight prepares
#: per world is kept by :func:`ideas_hpc.flyby.world.cached_static`.
_NOMINAL: dict = {}
#: Largest ``||C C^T - I||_F`` accepted for the perturbed DCMs (the kernels assume
#: ``||C||_2 <= 1 + 1e-9``); anything worse takes the full recomputation.
ORTHO_TOL = 1e-10


@dataclass
class RowEngine:
    """Nominal data of one set of candidates (see module docstring)."""

    setup: FlybySetup
    theta: np.ndarray
    r0_T: np.ndarray
    v0_T: np.ndarray
    witness: np.ndarray | None = None      # (K, V) int32
    slack_q: np.ndarray | None = None      # (K, V) float32, m
    radius: np.ndarray | None = None       # (K, V) float32, m
    window: np.ndarray | None = None       # (K, V, 2) int32
    unseen_any: np.ndarray | None = None   # (K, V) int32
    budget: tuple = (0.0, 0.0)             # (Frobenius, m)
    #: Fly only what the rows read (the one-pass closed loop when it covers the scenario,
    #: same bits); False flies the flyby pipeline's whole flight, time series and all
    #: (the benchmark's baseline).
    one_pass: bool = True

    @property
    def fast(self) -> bool:
        return not self.setup.coverage.requirement

    token: str = field(default_factory=lambda: uuid.uuid4().hex)

    def _cached(self) -> dict:
        """This process's nominal flight of the engine (by ``token``): large and cheap to
        recompute, so never shipped; each process keeps the last two engines', since
        every chunk task unpickles its own copy."""
        got = _NOMINAL.get(self.token)
        if got is None:
            got = {"flight": self._nominal_flight()}
            while len(_NOMINAL) >= 2:
                _NOMINAL.pop(next(iter(_NOMINAL)))
            _NOMINAL[self.token] = got
        return got

    def _nominal_flight(self):
        """The nominal world's flight with perfect tracking, at the images (the one flight
        path: only the positions at the images are integrated unless the camera
        follows the track, 0.03 against 0.13 s for 720 candidates, in every worker)."""
        ideal = self.setup.with_(attitude_mode=perfect_tracking())
        v = flight_views(ideal, self.theta, None, self.r0_T, self.v0_T, Perturbation(),
                         plan=FlightPlan(series=False))
        return v.r_img_T, v.imaging_BT

    def nominal(self):
        """Positions and ideal camera DCMs of the nominal flight at the images."""
        return self._cached()["flight"]

    def _static(self):
        """The kernels' records of the nominal flight, validated once per process; the
        mesh, its BVH and the lighting are the nominal world's (kept per world)."""
        got = self._cached()
        if "records" not in got:
            setup = self.setup
            shape = setup.body.shape
            r, c, tan_eta, near, far, _ = check_geometry(shape, *got["flight"], setup.eta_rad,
                                                         setup.near_m, setup.far_m)
            mesh, opts, bvh = world_records(setup, setup.world, r.shape[1])
            cam = camera_record(r, c, np.zeros(r.shape[1]), tan_eta, near, far,
                                setup.coverage.mode == "exact")
            got["records"] = (mesh, cam, opts, bvh)
        return got["records"]

    def prepare(self, pilot: Perturbation | None) -> "RowEngine":
        """The budget (from the pilot perturbation), then the proofs: windows and witnesses."""
        if not self.fast:
            return self
        r_img, dcm = self.nominal()
        mesh, cam, opts, bvh = self._static()
        first = first_image_by_spacecraft(mesh, cam, opts, bvh)
        if pilot is not None:
            rp, dp = self.flight(pilot)
            dev_r = np.linalg.norm(rp - r_img, axis=2)
            dev_c = np.sqrt(((dp - dcm) ** 2).sum(axis=(2, 3)))
            half = dev_c.shape[1] // 2
            br = HEADROOM * float(np.percentile(dev_r.max(axis=1), 99))
            bc = HEADROOM * float(np.percentile(dev_c[:, half:].max(axis=1), 99))
            self.budget = (bc, br)
        bc, br = self.budget
        window = windows(mesh, cam, opts, bvh, float(bc), float(br), True)
        witness, slack_q, radius = witness_proofs(first, window, mesh, cam, opts, bvh, float(bc),
                                                  float(br))
        # shipped to every worker: float32 rounded down (a proof may only shrink)
        self.slack_q, self.radius = _down32(slack_q), _down32(radius)
        self.witness = witness.astype(np.int32)
        self.window = window.astype(np.int32)
        self.unseen_any = windows(mesh, cam, opts, bvh, BC_ANY, float(br), False)[:, :, 0] \
            .astype(np.int32)
        return self

    def world(self, pert: Perturbation) -> World:
        """The world of a scenario with draws ``pert`` (its ``params_override``)."""
        return self.setup.world.perturbed(pert.params_override)

    def flight(self, pert: Perturbation, reuse: bool = False, world: World | None = None):
        """Positions and imaging camera DCMs at the images of the perturbed flight, through
        ``world`` (default: :meth:`world` of ``pert``).

        ``reuse``: the positions and DCMs may live in this thread's buffers of the
        engine, valid until its next ``flight(..., reuse=True)`` (the bank's chunks)."""
        buffers = None
        if reuse:   # one buffer per thread: a worker may run chunks of one engine in threads
            buffers = (self._cached().setdefault("buffers", {})
                       .setdefault(threading.get_ident(), {}))
        v = flight_views(self.setup, self.theta, None, self.r0_T, self.v0_T, pert, world=world,
                         plan=FlightPlan(series=not self.one_pass, buffers=buffers))
        return v.r_img_T, v.imaging_BT

    def scenario_rows(self, pert: Perturbation, reuse: bool = False) -> np.ndarray:
        """(K, V) bool rows of the scenario with draws ``pert``: its world, its flight,
        its rows."""
        world = self.world(pert)
        return self.rows(*self.flight(pert, reuse, world), world=world)

    def rows(self, r_img, dcm, world: World | None = None) -> np.ndarray:
        """(K, V) bool rows of a perturbed flight through ``world`` (default: the nominal
        one), identical to the full recomputation."""
        if world is not None and (world.mapping_key(self.setup)
                                  != self.setup.world.mapping_key(self.setup)):
            return self._full(r_img, dcm, world)     # another shape or Sun: no proofs
        if not self.fast:
            return self._full(r_img, dcm)
        if self.witness is None:    # no proofs prepared (a target prior's engine)
            return self._full(r_img, dcm, world)
        r = np.ascontiguousarray(r_img, dtype=np.float64)
        c = np.ascontiguousarray(dcm, dtype=np.float64)
        r_nom, dcm_nom = self.nominal()
        if r.shape != r_nom.shape or c.shape != dcm_nom.shape:
            return self._full(r_img, dcm)
        mesh, cam0, opts, bvh = self._static()
        cam = cam0._replace(r_T_m=r, dcm_BT=c)
        n = r.shape[0]
        nominal = Nominal(self.witness, self.slack_q, self.radius, self.window, self.unseen_any,
                          np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64), r_nom,
                          dcm_nom, np.array([*map(float, self.budget), ORTHO_TOL]))
        rows = _k.perturbed_rows(nominal, mesh, cam, opts, bvh)
        # the proofs need near-orthonormal DCMs; anything else (or non-finite
        # input, which the full path rejects by name) takes the validated full path
        if np.any(nominal.i_ok < 0):
            return self._full(r_img, dcm)
        return rows

    def first_seen(self, r_img, dcm, world: World | None = None) -> np.ndarray:
        """(K, V) int64: the first image at which each candidate sees each vertex on this
        flight through ``world`` (default: the nominal one), -1 never (seen mode; the
        validation's losses in the pass, issue 41)."""
        _, cam0, _, _ = self._static()
        world = self.setup.world if world is None else world
        cam = cam0._replace(r_T_m=np.ascontiguousarray(r_img, dtype=np.float64),
                            dcm_BT=np.ascontiguousarray(dcm, dtype=np.float64))
        mesh, opts, bvh = world_records(self.setup, world, cam.r_T_m.shape[1])
        return first_image_by_spacecraft(mesh, cam, opts, bvh)

    def _full(self, r_img, dcm, world: World | None = None) -> np.ndarray:
        """Rows without the nominal flight's proofs: from the world's statics."""
        return world_rows(self.setup, world, r_img, dcm)


def world_records(setup: FlybySetup, world: World, n_img: int) -> tuple:
    """``(Mesh, Strict, Bvh)`` of ``world``'s shape and Sun at ``setup``'s images for its
    coverage options: per-world statics (:func:`world_statics_of`)."""
    return world_statics_of(setup, world, n_img)[:3]


def world_statics_of(setup: FlybySetup, world: World, n_img: int) -> WorldStatics:
    """The :class:`~ideas_hpc.mapping.world_rows.WorldStatics` of ``world`` at ``setup``'s
    images (mesh, strict options with the Sun, BVH, lighting), built once per world and
    process (:func:`ideas_hpc.flyby.world.cached_static`, keyed by what they read)."""
    return cached_static(("mapping", setup.flight_key, world.mapping_key(setup), int(n_img)),
                         lambda: world_statics(world.shape, setup.coverage,
                                               world.sun_at_images(setup), int(n_img)))


def world_rows(setup: FlybySetup, world: World | None, r_img, dcm) -> np.ndarray:
    """(K, V) bool rows of a flight through ``world`` (default: ``setup``'s) from its
    per-world statics (:func:`~ideas_hpc.mapping.world_rows.rows_of_world`): every
    candidate of the world shares its mesh, BVH and lighting, and a mapped row stops at
    its first usable image. Identical to :func:`full_rows_of` (which it falls back to
    for input of the wrong rank, so that the full path names the error)."""
    world = setup.world if world is None else world
    if np.ndim(r_img) != 3:
        return full_rows_of(setup, world, r_img, dcm)
    st = world_statics_of(setup, world, np.shape(r_img)[1])
    return rows_of_world(st, setup.coverage, r_img, dcm, setup.image_times,
                         (setup.eta_rad, setup.near_m, setup.far_m),
                         getattr(setup, "device", "cpu"))


def _down32(x: np.ndarray) -> np.ndarray:
    """``x`` as float32, each value rounded toward -inf."""
    y = x.astype(np.float32)
    up = y.astype(np.float64) > x
    y[up] = np.nextafter(y[up], np.float32(-np.inf))
    return y


def rows_setup(setup: FlybySetup) -> FlybySetup:
    """The setup the rows are flown with: closed-loop time series not kept (one sample)."""
    if not setup.attitude.closed_loop:
        return setup
    return setup.with_(decimate=max(1, int(round((setup.tf_s - setup.t0_s) / setup.dt_s))))


def full_rows_of(setup: FlybySetup, world: World | None, r_img, dcm) -> np.ndarray:
    """(K, V) bool rows of a flight through ``world`` (default: ``setup``'s) by full
    recomputation: its shape, its Sun."""
    world = setup.world if world is None else world
    return rows_from_views(world.flown(setup), r_img, dcm, world.sun_at_images(setup))


def full_rows(setup: FlybySetup, theta, periods, r0_T, v0_T, pert: Perturbation) -> np.ndarray:
    """(K, V) bool rows by full recomputation: the flyby pipeline's whole flight (time
    series and trajectory) through the scenario's world."""
    world = setup.world.perturbed(pert.params_override)
    v = flight_views(rows_setup(setup), theta, periods, r0_T, v0_T, pert, world=world)
    return full_rows_of(setup, world, v.r_img_T, v.imaging_BT)
