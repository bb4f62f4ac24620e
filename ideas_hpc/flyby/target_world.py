"""The worlds of a target prior as flights' worlds: one per scenario (SPEC 7f, issue 42).

A scenario bank whose setup carries a target prior (``FlybySetup.target``, a
:class:`~ideas_hpc.body.target_prior.TargetPrior`) flies, in scenario ``s`` of design
stream ``f``, world ``prior.draw(seed, s, family=f)``
(:func:`ideas_hpc.base.seeds.world_rng`): the bank's, the validation's and the
held-out scenarios' streams are distinct families, so they share no world, and world
``s`` depends on ``(seed, f, s)`` only (never on the chunking or the worker count).

The flight frame
----------------
Every flight of a campaign is flown in the campaign's nominal frame ``T0``: the
frame of its body's pole and prime meridian, in which the encounter (approach
direction, ring, cameras) and the Sun are resolved once by the setup. The spacecraft
are navigated inertially, so a world whose body is turned another way is the same
swarm, the same Sun and the same approach around a *turned body*: the drawn shape,
given in its own body frame ``T_w``, is placed in ``T0`` at closest approach (TCA)::

    v_T0 = [T0 N](t_ca) [T_w N](t_ca)^T v_Tw,     [T N](t) = R3(W(t)) [P N](pole)

(:mod:`ideas_hpc.core.dynamics.ephemeris`'s frames; ``W_w(t_ca)`` is the world's drawn
rotation phase at TCA, ``W_0(t_ca) = W0 + omega (epoch_s + t_ca)`` the nominal's). The
flight frame keeps spinning about the nominal axis at the nominal rate: over an
encounter's imaging window ``dt`` the turned body's true motion differs from that by
at most ``omega dt`` times the pole offset (Eros-class, 10 km/s, 6 s: 0.11 deg times
``sin`` of a ~10 deg offset, 0.02 deg), which is neglected. So the world's parameters
keep the nominal pole, spin and prime meridian (the Sun in ``T0`` is the nominal's);
``mu`` scales with the drawn volume at the nominal bulk density and C20/C22 are the
drawn shape's in its own frame (:meth:`~ideas_hpc.body.target_prior.TargetWorld.physical_params`;
gravity moves a 10 km/s pass by millimetres). A polyhedron gravity term reads the
turned mesh itself.

Every world shares the nominal mesh's topology (vertex count and faces), so rows stay
``(S, C, V)``; the vertex areas are each world's own (:func:`world_areas`).
"""

from __future__ import annotations

import dataclasses
import threading
from collections import OrderedDict

import numpy as np

from ideas_hpc.body.bodies import Body
from ideas_hpc.body.shape import build_shape
from ideas_hpc.dynamics.trajectory import body_dcm_TN
from ideas_hpc.flyby.reference_area import reference_areas
from ideas_hpc.flyby.world import World

#: Drawn worlds kept per process (a bank chunk's worlds are drawn again for its areas).
WORLDS_KEPT = 64
_WORLDS: OrderedDict = OrderedDict()
_LOCK = threading.Lock()


def dcm_TN(params, pole_lon_lat=None, w_rad: float = 0.0) -> np.ndarray:
    """``[T N] = R3(W) [P N]`` for the pole ``(lambda, beta)`` in N (rad; default
    ``params``' own pole, or its orbit normal) at rotation angle ``w_rad``
    (:func:`~ideas_hpc.dynamics.trajectory.body_dcm_TN`)."""
    return body_dcm_TN(params, w_rad, pole_lon_lat)


def t_tca_s(setup) -> float:
    """Flyby time of closest approach: the encounter's, or the paper pass's mid-window."""
    if setup.encounter is not None:
        return float(setup.encounter.t_ca_s)
    return 0.5 * (float(setup.t0_s) + float(setup.tf_s))


def nominal_dcm_TN(setup) -> np.ndarray:
    """``[T0 N]`` at TCA of ``setup``'s nominal body (module docstring)."""
    p = setup.body.require_params()
    return dcm_TN(p, None, p.prime_meridian + p.spin_rate * (setup.epoch_s + t_tca_s(setup)))


def placed_world(setup, tw) -> World:
    """The flights' :class:`World` of a drawn :class:`~ideas_hpc.body.target_prior.TargetWorld`
    ``tw``: its shape turned into ``T0`` and its volume-scaled parameters (module
    docstring), ``setup``'s force model, epoch and encounter."""
    base = setup.body.require_params()
    q = nominal_dcm_TN(setup) @ dcm_TN(base, tw.pole_lon_lat_rad, tw.phase_tca_rad).T
    sh = tw.shape
    shape = build_shape(sh.vertices_T @ q.T, sh.faces, name=sh.name, source=sh.source)
    p = tw.physical_params(base, t_tca_s(setup),
                           reference_volume_m3=setup.body.shape.mass_properties.volume_m3)
    p = dataclasses.replace(p, pole_ra=base.pole_ra, pole_dec=base.pole_dec,
                            spin_period=base.spin_period, prime_meridian=base.prime_meridian)
    body = Body(setup.body.name, shape, p, f"{setup.body.note}; {sh.source}")
    return World(body, setup.force_model, setup.epoch_s, setup.encounter)


def drawn_world(setup, seed: int, family: int, k: int) -> World:
    """World ``k`` of design stream ``family`` under ``setup.target`` (kept per process)."""
    prior = setup.target
    # a prior of one world (a given truth, ``one_world``) is placed once, not per draw
    draw = (0, 0, 0) if getattr(prior, "one_world", False) else (int(seed), int(family), int(k))
    key = (id(prior), id(setup.body), *draw)
    with _LOCK:
        got = _WORLDS.get(key)
        if got is not None and got[0] is prior and got[1] is setup.body:
            _WORLDS.move_to_end(key)
            return got[2]
    world = placed_world(setup, prior.draw(int(seed), int(k), family=int(family)))
    with _LOCK:
        _WORLDS[key] = (prior, setup.body, world)
        while len(_WORLDS) > WORLDS_KEPT:
            _WORLDS.popitem(last=False)
    return world


def scenario_world(setup, seed: int, family: int, k: int, params_override=None) -> World:
    """The world of draw ``k`` of stream ``family``: ``setup``'s nominal world (no target
    prior) or the drawn one, with the scenario's parameter draws on top."""
    base = setup.world if setup.target is None else drawn_world(setup, seed, family, k)
    return base.perturbed(params_override)


def world_areas(setup, seed: int, family: int, ks, requirement=None) -> np.ndarray:
    """Vertex areas, m^2: ``(V,)`` of the nominal body without a target prior, else
    ``(len(ks), V)``, row ``i`` world ``ks[i]``'s of stream ``family``. With a
    ``requirement`` (:class:`~ideas_hpc.mapping.requirement.Requirement`), each world's
    reference area instead (:func:`~ideas_hpc.flyby.reference_area.reference_areas`: the
    surface lit at closest approach in that world, its own shape under the Sun)."""
    if requirement is not None:
        if setup.target is None:
            return reference_areas(setup, requirement)
        return np.stack([reference_areas(drawn_world(setup, seed, family, int(k)).flown(setup),
                                         requirement) for k in ks])
    if setup.target is None:
        return np.asarray(setup.body.shape.vertex_areas, dtype=np.float64)
    return np.stack([drawn_world(setup, seed, family, int(k)).shape.vertex_areas for k in ks])
