"""The world a flight flies through: one record per scenario (issue 40).

A :class:`World` holds what a scenario may change about the target and its
encounter, and nothing about the swarm:

* the body: its shape and mass properties (:class:`~ideas_hpc.body.bodies.Body`),
  its pole, spin rate and rotation phase (``pole_ra``, ``pole_dec``,
  ``spin_period``, ``prime_meridian`` of its
  :class:`~ideas_hpc.body.params.PhysicalParams`);
* the Sun: the body's heliocentric orbit and the arrival epoch ``epoch_s``
  (:meth:`World.sun_T`, the one place a flight reads the Sun);
* the encounter: approach, speed and time of closest approach
  (:class:`~ideas_hpc.flyby.encounter.Encounter`; None: the paper's geometry);
* the force model and its parameters (``mu``, ``c20``, ``c22``, ``reflectivity``
  and every other numeric body parameter): :meth:`World.forces`, packed once.

A campaign's setup flies its nominal world (:attr:`FlybySetup.world
<ideas_hpc.flyby.flight.FlybySetup.world>`); a scenario's world is that one with
the parameters its dispersions drew (:meth:`World.perturbed`, the
``params_override`` of a :class:`~ideas_hpc.flyby.flight.Perturbation`): one
list of what may be perturbed, :func:`ideas_hpc.dynamics.force_model.world_parameters`.

What a flight prepares from a world and not from a scenario's other draws (ring
frames, spin tables, the reference at the first step, the ideal cameras, the
BVH and the lighting) is kept per process in :func:`cached_static`, keyed by the
parts of the world it reads (:attr:`World.attitude_key`, :meth:`World.mapping_key`),
so scenarios that share them (gravity and reflectivity draws on one body) share it,
and a scenario with another pole, spin or shape gets its own (the worlds of a target
prior, :mod:`ideas_hpc.flyby.target_world`: every key holds the shape's digest).
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import threading
from collections import OrderedDict
from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable

import numpy as np

from ideas_hpc.body.bodies import Body
from ideas_hpc.body.params import PhysicalParams
from ideas_hpc.dynamics.force_model import ForceModel, apply_override, pack_force_model
from ideas_hpc.dynamics.forces import PackedForceModel
from ideas_hpc.dynamics.trajectory import sun_direction_T
from ideas_hpc.flyby.encounter import Encounter
from ideas_hpc.flyby.usable import scene_radius_m

#: Per-world statics kept per process (:func:`cached_static`); the least recently used
#: go first. Few: one entry can be large (720 candidates' ideal cameras at 601 images
#: are 31 MB), and a bank's scenarios on one body share theirs.
STATICS_KEPT = 6
_STATICS: OrderedDict = OrderedDict()
_LOCK = threading.Lock()
#: ``id(shape) -> (shape, digest)``: a mesh is hashed once per process.
_SHAPE_DIGESTS: dict = {}


@dataclass(frozen=True)
class World:
    """One scenario's target, Sun, encounter and force model (module docstring). SI.

    Attributes
    ----------
    body : Body
        Shape and the body's own (nominal) parameters.
    force_model : ForceModel
        The ``[dynamics]`` model (its own reflectivity).
    epoch_s : float
        Arrival epoch, s after the element epoch (the Sun at flyby time ``t`` is
        read at ``epoch_s + t``).
    encounter : Encounter or None
        A real encounter's approach and time of closest approach; None: the paper's
        pole-aligned pass.
    parameters : tuple of (str, float)
        The parameters of this world that depart from the body's and the force
        model's own, sorted by name (:meth:`perturbed`).
    """

    body: Body
    force_model: ForceModel = field(default_factory=ForceModel)
    epoch_s: float = 0.0
    encounter: Encounter | None = None
    parameters: tuple = ()

    def perturbed(self, parameters: dict | None) -> "World":
        """This world with ``parameters`` (``{name: SI value}``, any of
        :func:`~ideas_hpc.dynamics.force_model.world_parameters`) set; checked by name."""
        if not parameters:
            return self
        merged = dict(self.parameters)
        merged.update(parameters)
        apply_override(self.body.require_params(), self.force_model, merged)  # checks
        return dataclasses.replace(self, parameters=tuple(sorted(merged.items())))

    @cached_property
    def params(self) -> PhysicalParams:
        """The body's parameters in this world (pole, spin, phase, gravity, orbit)."""
        if not self.parameters:
            return self.body.params
        return apply_override(self.body.require_params(), self.force_model,
                              dict(self.parameters))[0]

    @cached_property
    def flown_body(self) -> Body:
        """:attr:`body` with :attr:`params`: what the flight's models read."""
        if not self.parameters:
            return self.body
        return dataclasses.replace(self.body, params=self.params)

    @cached_property
    def flown_force_model(self) -> ForceModel:
        """:attr:`force_model` with this world's reflectivity."""
        if not self.parameters:
            return self.force_model
        refl = apply_override(self.body.require_params(), self.force_model,
                              dict(self.parameters))[1]
        return dataclasses.replace(self.force_model, reflectivity=refl)

    @property
    def shape(self):
        return self.body.shape

    @property
    def spin_rate_rad_s(self) -> float:
        return float(self.params.spin_rate)

    @property
    def pole_rad(self) -> tuple[float, float]:
        """The spin pole's right ascension and declination in N (ecliptic), rad: the
        body's, or the orbit normal ``h = (sin i sin RAAN, -sin i cos RAAN, cos i)`` when
        it has none (SPEC section 4, :mod:`ideas_hpc.core.dynamics.ephemeris`)."""
        p = self.params
        if p.pole_ra is not None and p.pole_dec is not None:
            return float(p.pole_ra), float(p.pole_dec)
        si = math.sin(p.orbit_i)
        h = (si * math.sin(p.orbit_raan), -si * math.cos(p.orbit_raan), math.cos(p.orbit_i))
        return math.atan2(h[1], h[0]), math.asin(max(-1.0, min(1.0, h[2])))

    @cached_property
    def forces(self) -> PackedForceModel:
        """The kernels' force record of this world (packed once)."""
        return pack_force_model(self.body, self.force_model, dict(self.parameters) or None)

    def sun_T(self, times_s) -> np.ndarray:
        """Unit body -> Sun directions (n, 3) in T at flyby times ``times_s`` (s)."""
        return sun_direction_T(self.params, self.epoch_s + np.asarray(times_s, dtype=np.float64))

    def sun_at_images(self, setup) -> np.ndarray | None:
        """The Sun at ``setup``'s image times when its coverage reads it, else None."""
        if not setup.coverage.needs_sun:
            return None
        return self.sun_T(setup.image_times)

    def flown(self, setup):
        """``setup`` (a :class:`~ideas_hpc.flyby.flight.FlybySetup`) in this world: its
        body, force model, epoch and encounter replaced by this world's."""
        if (not self.parameters and setup.body is self.body
                and setup.force_model is self.force_model and setup.epoch_s == self.epoch_s
                and setup.encounter == self.encounter):
            return setup
        return dataclasses.replace(setup, body=self.flown_body,
                                   force_model=self.flown_force_model, epoch_s=self.epoch_s,
                                   encounter=self.encounter)

    @cached_property
    def attitude_key(self) -> tuple:
        """What the closed loop and the ideal cameras read of this world: the spin, the
        encounter, the bounding radius (blinding) and the footprint sphere's radius (smear,
        :func:`~ideas_hpc.flyby.usable.scene_radius_m`), and the mesh itself (its digest):
        worlds of a target prior never share statics (issue 42)."""
        return (self.spin_rate_rad_s, repr(self.encounter), float(self.shape.r_max),
                scene_radius_m(self.shape), shape_digest(self.shape))

    def mapping_key(self, setup) -> tuple:
        """What a flight's rows read of this world besides the flight: the shape, and
        the Sun when ``setup``'s coverage reads it."""
        p = self.params
        sun = None
        if setup.coverage.needs_sun:
            sun = (p.orbit_a, p.orbit_e, p.orbit_i, p.orbit_raan, p.orbit_argp, p.orbit_nu,
                   p.pole_ra, p.pole_dec, p.spin_rate, p.prime_meridian, self.epoch_s)
        return (shape_digest(self.shape), sun)


def shape_digest(shape) -> str:
    """SHA-256 of a mesh's vertices and faces (once per shape object and process)."""
    got = _SHAPE_DIGESTS.get(id(shape))
    if got is not None and got[0] is shape:
        return got[1]
    d = hashlib.sha256(np.ascontiguousarray(shape.vertices_T).tobytes()
                       + np.ascontiguousarray(shape.faces).tobytes()).hexdigest()
    if len(_SHAPE_DIGESTS) >= 16:
        _SHAPE_DIGESTS.pop(next(iter(_SHAPE_DIGESTS)))
    _SHAPE_DIGESTS[id(shape)] = (shape, d)
    return d


def array_key(*arrays) -> str:
    """A digest of arrays (or None) for static keys: dtype, shape and bytes."""
    h = hashlib.sha1()
    for a in arrays:
        if a is None:
            h.update(b"none")
            continue
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def cached_static(key: tuple, build: Callable):
    """``build()``, kept per process under ``key`` (a tuple naming what it reads of the
    world, the setup and the swarm); the :data:`STATICS_KEPT` most recent are kept."""
    with _LOCK:
        got = _STATICS.get(key)
        if got is not None:
            _STATICS.move_to_end(key)
            return got
    value = build()
    with _LOCK:
        _STATICS[key] = value
        while len(_STATICS) > STATICS_KEPT:
            _STATICS.popitem(last=False)
    return value
