"""The packed controller and RK4 step of the bank's closed loop take their rare MRP
branches lane by lane, with the same bits as the scalar pipeline (issue 31).

:func:`~ideas_hpc.core.attitude.lanes_control._control_lanes` computes the common
side of every lane and recomputes only the lanes where the MRP addition or
subtraction flips an operand (``|den| < 0.1``) or switches its result to the shadow
set; ``_rk4_lanes`` switches only the lanes that cross ``|sigma| = 1``. These
states are built so that every such branch is taken on some lanes and none on
others, and each lane is compared with the scalar kernels the pipeline flies
(:func:`~ideas_hpc.core.attitude.control.sliding_mode_into` on the reference of
:func:`~ideas_hpc.core.attitude.maneuvers.nadir_reference_into`, and
:func:`~ideas_hpc.core.attitude.rigid_body.rk4_step_into`).
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.core.attitude.camera_lanes import _rk4_lanes
from ideas_hpc.core.attitude.control import sliding_mode_into
from ideas_hpc.core.attitude.lanes_control import (_D, _NROW, _OR, _RARE, _SR, _U, _X, _Z,
                                                   LANES, _control_lanes)
from ideas_hpc.core.attitude.mrp import mrp_add_s, mrp_sub_s
from ideas_hpc.core.attitude.records import ControlGains, Wheels
from ideas_hpc.core.attitude.rigid_body import rk4_step_into

GAINS = ControlGains(np.array([0.11, 0.12, 0.13]), np.array([1e-3, 2e-3, 3e-3]),
                     np.array([2e-3, 2e-3, 2e-3]), np.array([40.0, 45.0, 50.0]), 0.2)
WHEELS = Wheels(np.array([180.0, 160.0, 140.0]), np.array([0.05, 0.05, 0.05]), 0.01, 0.05)


def _row(S, r, lane):
    return np.array([S[(r + j) * LANES + lane] for j in range(3)])


def _put(S, r, lane, v):
    for j in range(3):
        S[(r + j) * LANES + lane] = v[j]


def _unit(rng):
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def _control_state(rng, tz):
    """A lanes' state whose lanes take, in turn: nothing rare, the reference's switch,
    the subtraction's flip and the subtraction's switch."""
    S = np.zeros(_NROW * LANES)
    kinds = np.arange(LANES) % 4
    for lane in range(LANES):
        k = kinds[lane]
        s_rt = 0.3 * _unit(rng)
        if k == 1:            # sigma_RT near 180 deg about z: the sum with tz z switches
            s_rt = np.array([0.01, -0.02, 0.995])
        r = np.array(mrp_add_s(0.0, 0.0, tz, *s_rt))
        s_bn = np.array(mrp_add_s(*(0.01 * _unit(rng)), *r))   # near the reference
        if k == 2:            # the shadow set of (nearly) the reference: den ~ 0, flip
            s_bn = -r / (r @ r) + 1e-4 * _unit(rng)
        elif k == 3:          # 200 deg away from the reference: the error switches
            s_bn = np.array(mrp_add_s(*(np.tan(np.radians(200.0) / 4) * _unit(rng)), *r))
            s_bn = s_bn if s_bn @ s_bn <= 1.0 else -s_bn / (s_bn @ s_bn)
        _put(S, _SR, lane, s_rt)
        _put(S, _OR, lane, 1e-3 * _unit(rng))
        _put(S, _X, lane, s_bn)
        _put(S, _X + 3, lane, 1e-3 * rng.normal(size=3))
        _put(S, _X + 6, lane, 50.0 * rng.normal(size=3))
        _put(S, _Z, lane, 0.01 * rng.normal(size=3))
    return S


def _rare_branches(S, lane, tz):
    """(the reference's switch, the error's flip, the error's switch) of the scalar path."""
    a = np.array([0.0, 0.0, tz])
    b = _row(S, _SR, lane)
    den_a = 1.0 + (a @ a) * (b @ b) - 2.0 * (a @ b)
    x = ((1 - a @ a) * b + (1 - b @ b) * a - 2 * np.cross(b, a)) / den_a
    switch_ref = abs(den_a) >= 0.1 and x @ x > 1.0
    r = np.array(mrp_add_s(*a, *b))
    s = _row(S, _X, lane)
    den = 1.0 + (r @ r) * (s @ s) + 2.0 * (r @ s)
    flip = abs(den) < 0.1
    d = ((1 - r @ r) * s - (1 - s @ s) * r + 2 * np.cross(s, r)) / den
    return switch_ref, flip, (not flip) and d @ d > 1.0


def test_packed_controller_takes_every_rare_branch_as_the_scalar_one():
    rng = np.random.default_rng(3)
    tz = np.tan(0.25 * 3.3e-4 * 120.0)
    S = _control_state(rng, tz)
    _control_lanes(S, tz, GAINS, WHEELS)
    rare = np.array([S[_RARE * LANES + lane] for lane in range(LANES)]) != 0.0
    # the lanes whose scalar MRP algebra takes a rare branch (S&J 3.150 and the flip
    # of mrp_add_s / mrp_sub_s), each kind on some lanes, are flagged, the others not
    taken = np.array([_rare_branches(S, lane, tz) for lane in range(LANES)])
    assert taken.any(axis=0).all() and not taken.all(axis=1).any()
    np.testing.assert_array_equal(rare, taken.any(axis=1))
    for lane in range(LANES):
        x = np.concatenate([_row(S, _X, lane), _row(S, _X + 3, lane), _row(S, _X + 6, lane)])
        ref = np.zeros(9)
        ref[:3] = mrp_add_s(0.0, 0.0, tz, *_row(S, _SR, lane))
        ref[3:6] = _row(S, _OR, lane)
        u, err = np.empty(3), np.empty(6)
        sliding_mode_into(x, _row(S, _Z, lane), ref, GAINS, WHEELS, np.zeros(3), u, err)
        assert _row(S, _U, lane).tobytes() == u.tobytes(), lane
        assert _row(S, _D, lane).tobytes() == err[:3].tobytes(), lane
        # and the error is the scalar subtraction's (switched where it must be)
        assert err[:3].tobytes() == np.array(mrp_sub_s(*x[:3], *ref[:3])).tobytes()


def test_packed_rk4_switches_the_lanes_that_cross_the_unit_sphere():
    rng = np.random.default_rng(4)
    dt = 0.1
    S = np.zeros(_NROW * LANES)
    crossing = np.arange(LANES) % 3 == 0
    for lane in range(LANES):
        axis = _unit(rng)
        # |sigma| just below 1 spinning away from the origin: the step crosses it
        s = (0.99999 if crossing[lane] else 0.5) * axis
        _put(S, _X, lane, s)
        _put(S, _X + 3, lane, 0.05 * axis + 1e-3 * rng.normal(size=3))
        _put(S, _X + 6, lane, 30.0 * rng.normal(size=3))
        _put(S, _U, lane, 1e-3 * rng.normal(size=3))
        _put(S, _D, lane, 0.01 * rng.normal(size=3))
    before = S.copy()
    _rk4_lanes(S, WHEELS.I_rw_kgm2, WHEELS.J_s_kgm2, dt, GAINS.int_limit)
    switched = 0
    for lane in range(LANES):
        x = np.concatenate([_row(before, _X + 3 * i, lane) for i in range(3)])
        out = np.empty(9)
        rk4_step_into(x, _row(before, _U, lane), np.zeros(3), WHEELS.I_rw_kgm2,
                      WHEELS.J_s_kgm2, dt, np.empty((5, 9)), out)
        got = np.concatenate([_row(S, _X + 3 * i, lane) for i in range(3)])
        assert got.tobytes() == out.tobytes(), lane
        switched += int(x[:3] @ out[:3] < 0.0)     # the shadow set points the other way
    assert switched == int(crossing.sum())
