"""The force record (core/forces.py) and the settings factory (forces.py).

Truths: the record's views give back the arrays that were packed (round trip);
the dispatcher equals a direct call of each gravity kernel; the settings list
packs to the same record as the ``[dynamics]`` table; bad settings name the field.
"""

from __future__ import annotations

import numpy as np
import pytest

from ideas_hpc.body.bodies import load_body
from ideas_hpc.core.dynamics import forces as F
from ideas_hpc.core.dynamics import gravity as gk
from ideas_hpc.base.errors import InputError
from ideas_hpc.dynamics.force_model import ForceModel, pack_force_model
from ideas_hpc.dynamics.force_terms import (CannonballSRP, Degree2, PointMass, Polyhedron,
                                            SphericalHarmonics)
from ideas_hpc.dynamics.forces import pack_forces

BODY = load_body("eros-ellipsoid", resolution=1)


def test_polyhedron_record_round_trip_and_dispatch():
    pk = pack_forces([Polyhedron(density=2670.0)], BODY.params, BODY.shape)
    v = np.ascontiguousarray(BODY.shape.vertices_T, dtype=np.float64)
    f = np.ascontiguousarray(BODY.shape.faces, dtype=np.int64)
    e, ed, fd = gk.polyhedron_precompute(v, f)
    for got, want in zip(F.polyhedron_arrays(*pk.args()), (v, f, e, ed, fd)):
        assert got.dtype == want.dtype and np.array_equal(got, want)
    r = np.array([30e3, -5e3, 12e3])
    a1, g1, a2, g2 = np.empty(3), np.empty((3, 3)), np.empty(3), np.empty((3, 3))
    u1 = F.gravity_T(r, *pk.args(), a1, g1, np.empty(3), np.empty((3, 3)))
    u2 = gk.polyhedron_gravity(r, 6.67430e-11 * 2670.0, v, f, e, ed, fd, a2, g2)
    assert u1 == u2 and np.array_equal(a1, a2) and np.array_equal(g1, g2)


def test_degree2_dispatch_is_point_mass_plus_degree2():
    pk = pack_forces([Degree2()], BODY.params)
    p = BODY.params
    r = np.array([30e3, -5e3, 12e3])
    acc, grad = np.empty(3), np.empty((3, 3))
    u = F.gravity_T(r, *pk.args(), acc, grad, np.empty(3), np.empty((3, 3)))
    a0, g0, a2, g2 = np.empty(3), np.empty((3, 3)), np.empty(3), np.empty((3, 3))
    u0 = gk.point_mass(r, p.mu, a0, g0) + gk.degree2(r, p.mu, p.c20, p.c22, a2, g2)
    assert u == u0 and np.array_equal(acc, a0 + a2) and np.array_equal(grad, g0 + g2)
    assert pk.ff[F.K_SRP] == 0.0 and F.sh_tables(*pk.args())[0].shape == (10, 0, 0)


def test_settings_list_packs_as_the_dynamics_table():
    fm = ForceModel(gravity="point_mass", srp=True, reflectivity=0.3, sc_mass=5.0)
    a = pack_force_model(BODY, fm)
    b = pack_forces([PointMass(), CannonballSRP(0.3, 5.0)], BODY.params)
    assert np.array_equal(a.fi, b.fi) and np.array_equal(a.ff, b.ff)
    assert fm.terms() == [PointMass(), CannonballSRP(0.3, 5.0)]


@pytest.mark.parametrize("build,field", [
    (lambda: SphericalHarmonics(sh_degree=1), "sh_degree"),
    (lambda: CannonballSRP(reflectivity=1.5), "reflectivity"),
    (lambda: Polyhedron(density=-1.0), "density"),
    (lambda: ForceModel(sc_mass=0.0), "sc_mass"),
    (lambda: pack_forces([PointMass(), Degree2()], BODY.params), "gravity"),
    (lambda: pack_forces([CannonballSRP()], BODY.params), "gravity"),
])
def test_bad_settings_name_the_field(build, field):
    with pytest.raises(InputError) as ei:
        build()
    assert ei.value.field == field
