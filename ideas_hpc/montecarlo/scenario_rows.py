"""Fast exact scenario rows: the nominal flight once, then only what a deviation can change.

Boundary of :mod:`ideas_hpc.core.mapping.scenario_rows`. :class:`RowEngine` flies the
candidates once on the nominal model with ideal attitude, records each
(candidate, vertex)'s first seeing image and whether any camera within a
deviation *budget* could see it, and then turns any perturbed flight
(positions and camera DCMs at the images) into rows identical to
:func:`ideas_hpc.design.candidates.rows_from_views` on that flight. The budget only
decides speed, never the rows; it is taken from a pilot scenario (the
deviations of scenario 0, with head room). Rows with a ``[coverage]``
requirement (quality masks) take the full recomputation. A closed-loop
scenario started on its reference is flown in one pass
(:mod:`ideas_hpc.montecarlo.scenario_flight`: the pipeline's flight, same bits).
"""

from __future__ import annotations

import threading
import uuid
from dataclasses import dataclass, field

import numpy as np

from ideas_hpc.design.candidates import rows_from_views
from ideas_hpc.montecarlo import scenario_flight as _flight
from ideas_hpc.core.mapping import scenario_rows as _k
from ideas_hpc.core.mapping.coverage import first_image_by_spacecraft
from ideas_hpc.core.mapping.scenario_proofs import BC_ANY, windows, witness_proofs
from ideas_hpc.flyby.camera import camera_at_images, imaging_dcms
from ideas_hpc.flyby.flight import FlybySetup, Perturbation, open_loop_views
from ideas_hpc.core.mapping.records import Nominal
from ideas_hpc.mapping.coverage import camera_record, check_geometry, mesh_record, strict_records

#: Head room on the pilot's deviations (speed only).
HEADROOM = 1.5
#: Per process: engine token -> its nominal flight and that flight's kernel records
#: (RowEngine._cached).
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
    #: Fly a closed-loop scenario in one pass (:mod:`~ideas_hpc.montecarlo.scenario_flight`,
    #: same bits); False flies the flyby pipeline (the benchmark's baseline).
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
        """:func:`~ideas_hpc.flyby.flight.open_loop_views` with ideal attitude, the same bits:
        without body tracking (which points at every step's position) only the
        positions at the images are integrated (0.03 against 0.13 s for 720
        candidates, in every worker)."""
        ideal = self.setup.with_(attitude_mode="ideal")
        if ideal.maneuver.tracks_body or ideal.encounter is not None:
            r_img, dcm, _, _ = open_loop_views(ideal, self.theta, None, self.r0_T, self.v0_T,
                                               Perturbation())
            return r_img, dcm
        t_img = _flight.image_times(ideal)
        r_img = _flight.positions_into(ideal, t_img, self.r0_T, self.v0_T, None,
                                       np.empty((len(self.r0_T), t_img.size, 3)))
        dcm, att = camera_at_images(ideal, self.theta, None, None, None, r_img)
        return r_img, imaging_dcms(ideal, dcm, att, r_img)

    def nominal(self):
        """Positions and ideal camera DCMs of the nominal flight at the images."""
        return self._cached()["flight"]

    def _static(self):
        """The kernels' records of the nominal flight, validated once per process."""
        got = self._cached()
        if "records" not in got:
            setup = self.setup
            shape = setup.body.shape
            r, c, tan_eta, near, far, _ = check_geometry(shape, *got["flight"], setup.eta_rad,
                                                         setup.near_m, setup.far_m)
            sun = setup.sun_T() if setup.coverage.needs_sun else None
            opts, bvh = strict_records(shape, setup.coverage, sun, r.shape[1])
            cam = camera_record(r, c, np.zeros(r.shape[1]), tan_eta, near, far,
                                setup.coverage.mode == "exact")
            got["records"] = (mesh_record(shape), cam, opts, bvh)
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

    def flight(self, pert: Perturbation, reuse: bool = False):
        """Positions and camera DCMs at the images of the perturbed flight.

        ``reuse``: the positions and DCMs may live in this thread's buffers of the
        engine, valid until its next ``flight(..., reuse=True)`` (the bank's chunks)."""
        if self.one_pass and _flight.covers(self.setup, pert):
            got = self._cached()
            if "statics" not in got:
                got["statics"] = _flight.flight_statics(self.setup, self.theta)
            # one buffer per thread: a worker may run chunks of one engine in threads
            buffers = (got.setdefault("buffers", {}).setdefault(threading.get_ident(), {})
                       if reuse else {})
            return _flight.fly_views(self.setup, got["statics"], self.r0_T, self.v0_T, pert,
                                     buffers)
        ideal = self.nominal()[1] if self.fast else None
        r_img, dcm, _, _ = open_loop_views(rows_setup(self.setup), self.theta, None, self.r0_T,
                                           self.v0_T, pert, ideal_dcm_BT=ideal)
        return r_img, dcm

    def rows(self, r_img, dcm) -> np.ndarray:
        """(K, V) bool rows of a perturbed flight, identical to the full recomputation."""
        if not self.fast:
            return self._full(r_img, dcm)
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

    def first_seen(self, r_img, dcm) -> np.ndarray:
        """(K, V) int64: the first image at which each candidate sees each vertex on this
        flight, -1 never (seen mode; the validation's losses in the pass, issue 41)."""
        mesh, cam0, opts, bvh = self._static()
        cam = cam0._replace(r_T_m=np.ascontiguousarray(r_img, dtype=np.float64),
                            dcm_BT=np.ascontiguousarray(dcm, dtype=np.float64))
        return first_image_by_spacecraft(mesh, cam, opts, bvh)

    def _full(self, r_img, dcm) -> np.ndarray:
        sun = self.setup.sun_T() if self.setup.coverage.needs_sun else None
        return rows_from_views(self.setup, r_img, dcm, sun)


def _down32(x: np.ndarray) -> np.ndarray:
    """``x`` as float32, each value rounded toward -inf."""
    y = x.astype(np.float32)
    up = y.astype(np.float64) > x
    y[up] = np.nextafter(y[up], np.float32(-np.inf))
    return y


def rows_setup(setup: FlybySetup) -> FlybySetup:
    """The setup the rows are flown with: closed-loop time series not kept (one sample)."""
    if setup.attitude_mode != "simulated":
        return setup
    return setup.with_(decimate=max(1, int(round((setup.tf_s - setup.t0_s) / setup.dt_s))))


def full_rows(setup: FlybySetup, theta, periods, r0_T, v0_T, pert: Perturbation) -> np.ndarray:
    """(K, V) bool rows by full recomputation: the flyby pipeline on the perturbed flight."""
    r_img, dcm, _, _ = open_loop_views(rows_setup(setup), theta, periods, r0_T, v0_T, pert)
    sun = setup.sun_T() if setup.coverage.needs_sun else None
    return rows_from_views(setup, r_img, dcm, sun)
