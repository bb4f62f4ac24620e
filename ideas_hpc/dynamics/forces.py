"""The force record of the flyby dynamics and its one factory (SPEC section 4).

ONE factory, :func:`pack_forces`, turns a list of settings objects
(:mod:`ideas_hpc.dynamics.force_terms`) into the record ``(fi, ff)`` of
:mod:`ideas_hpc.core.dynamics.forces` that every dynamics kernel takes::

    terms = [Degree2(), CannonballSRP(reflectivity=0.6, sc_mass=4.0, sc_area=BOX_AREA)]
    packed = pack_forces(terms, body.params, body.shape)

The ``[dynamics]`` table that chooses the terms is
:class:`ideas_hpc.dynamics.force_model.ForceModel`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ideas_hpc.base.constants import MU_SUN
from ideas_hpc.core.dynamics import forces as _cf
from ideas_hpc.dynamics.force_terms import GRAVITY_TERMS, CannonballSRP
from ideas_hpc.base.errors import InputError
from ideas_hpc.body.params import PhysicalParams


class PackedForceModel(NamedTuple):
    """The force record handed to the kernels (layout: :mod:`ideas_hpc.core.dynamics.forces`)."""

    fi: np.ndarray
    ff: np.ndarray

    def args(self):
        return (self.fi, self.ff)


def elements_and_pole(params: PhysicalParams):
    """Heliocentric elements (6,) and pole ``(ra, dec, flag)`` (3,) arrays of ``params``, SI."""
    elements = np.array([params.orbit_a, params.orbit_e, params.orbit_i, params.orbit_raan,
                         params.orbit_argp, params.orbit_nu], dtype=np.float64)
    pole = np.zeros(3)
    if params.pole_ra is not None and params.pole_dec is not None:
        pole[:] = (params.pole_ra, params.pole_dec, 1.0)
    return elements, pole


def pack_forces(terms, params: PhysicalParams, shape=None) -> PackedForceModel:
    """Build the kernels' force record from a list of settings objects.

    Parameters
    ----------
    terms : sequence
        Exactly one gravity term and at most one :class:`CannonballSRP`.
    params : PhysicalParams
        Body parameters (mu, C20, C22, spin, ephemeris; SI).
    shape : ideas_hpc.body.shape.Shape, optional
        Needed by :class:`Polyhedron`.
    """
    kinds = [type(t) for t in terms]  # one gravity term: the record has one MODEL_ code
    n_grav = sum(k in GRAVITY_TERMS for k in kinds)
    if n_grav != 1:
        raise InputError(f"need exactly one gravity term, got {n_grav}", field="gravity")
    if kinds.count(CannonballSRP) > 1:
        raise InputError("at most one CannonballSRP term", field="srp")
    empty3 = np.zeros((10, 0, 0))
    rec = {"srp_coef": 0.0, "g_rho": 0.0, "sh_gm": 0.0, "sh_r_ref": 0.0,
           "sh_ctab": empty3, "sh_stab": empty3,
           "poly": (np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64),
                    np.zeros((0, 2), dtype=np.int64), np.zeros((0, 3, 3)), np.zeros((0, 3, 3)))}
    for t in terms:
        if not hasattr(t, "_pack"):
            raise InputError(f"not a force settings object: {t!r}", field="terms")
        t._pack(rec, params, shape)
    elements, pole = elements_and_pole(params)
    consts = _cf.ForceConstants(*(float(x) for x in (
        params.mu, params.c20, params.c22, params.spin_rate, rec["srp_coef"], rec["g_rho"],
        rec["sh_gm"], rec["sh_r_ref"], params.prime_meridian, MU_SUN)))
    fi, ff = _cf.pack_record(rec["model"], consts, elements, pole,
                             _cf.HarmonicTables(rec["sh_ctab"], rec["sh_stab"]),
                             _cf.PolyhedronData(*rec["poly"]))
    return PackedForceModel(fi, ff)
