"""The batched closed loop of :mod:`ideas_hpc.core.attitude.batch` as a ``numba.cuda`` kernel.

One GPU thread flies one (sample, spacecraft) job over all steps, exactly the
loop of :func:`~ideas_hpc.core.attitude.batch.simulate_batch` (same step order,
same recorded quantities). The physics is not written twice: the kernel calls
the pure ``@njit`` functions of this folder (maneuver references, RK4 step, camera
DCM) through ``cuda.jit(device=True)`` wrappers of their Python source, and the
scalar helpers (``mrp_*_s``, ``wheel_limit_s``, ``_eom_s``) are compiled for the
device by Numba's CUDA target on first use; the sliding-mode law is
``control.sliding_mode_into`` itself (its clip ``sat_s`` is written with branches,
which this target compiles). One piece is mirrored here: the maneuver dispatch
(three lines, so that its array-taking branches are device functions the
simulator can run too).

Importing this module imports ``numba.cuda``: only
:mod:`ideas_hpc.attitude.device` does, and only when ``device = "cuda"``, so
CPU runs never pay for it. Under ``NUMBA_ENABLE_CUDASIM=1`` the same kernel
runs on Numba's CUDA simulator (the tests).

Floating point: the simulator evaluates the same IEEE double operations as the
CPU kernel; on a GPU, NVVM contracts multiply-adds into FMAs and libdevice's
``tan``/``atan``/``sin``/``cos`` may differ from the host's libm in the last
bit, so states agree to rounding, not bit for bit (docs/gpu.md).
"""

from __future__ import annotations

import math

import numpy as np
from numba import cuda, float64

from ideas_hpc.core.attitude.batch import _dcm_BT
from ideas_hpc.core.attitude.control import sliding_mode_into
from ideas_hpc.core.attitude.maneuvers import (FOV_MODE, NP_MODE, TRACK_MODE,
                                               fov_reference_into, nadir_reference_into)
from ideas_hpc.core.attitude.mrp import mrp_from_dcm
from ideas_hpc.core.attitude.records import (Initial, LoopSteps, Recorded, StepTables,
                                             SwarmReference)
from ideas_hpc.core.attitude.rigid_body import rk4_step_into

#: Threads per block (one job each), for few and for many jobs: a scenario's 720 jobs
#: in warp-sized blocks reach 23 multiprocessors instead of 12 (64 a block); many
#: scenarios at once fill the device either way, and larger blocks then keep more
#: warps resident per multiprocessor.
THREADS_FEW, THREADS_MANY = 32, 128
#: Jobs from which a batch counts as many.
MANY_JOBS = 16384

_nadir = cuda.jit(device=True)(nadir_reference_into.py_func)
_fov = cuda.jit(device=True)(fov_reference_into.py_func)
_rk4 = cuda.jit(device=True)(rk4_step_into.py_func)
_camera = cuda.jit(device=True)(_dcm_BT.py_func)


@cuda.jit(device=True)
def _reference(mode, t, spin_rate, sigma_RT, dcm_RT, theta_max, period, ref):
    """``core.attitude.maneuvers.reference_into`` for the modes a kernel flies (NP, FoV);
    its array-taking branches as device functions, so the simulator can run them too."""
    if mode == NP_MODE:
        _nadir(t, spin_rate, sigma_RT, dcm_RT, ref)
    else:
        _fov(t, spin_rate, sigma_RT, dcm_RT, theta_max, period, ref)


# the CPU's law itself (its clip is written with branches for this target)
_control = cuda.jit(device=True)(sliding_mode_into.py_func)


@cuda.jit
def _flights(swarm, gains, wheels, loop, initial, tables, out):
    """One thread per job ``smp * N + i``: the body of ``simulate_batch``'s ``prange``.
    Records (:mod:`~ideas_hpc.core.attitude.records`): ``swarm`` a
    :class:`SwarmReference`, ``loop`` a :class:`LoopSteps`, ``initial`` an
    :class:`Initial`, ``tables`` :class:`StepTables`, ``out`` a :class:`Recorded`."""
    sigma0 = initial.sigma_BN
    omega0 = initial.omega_BN_B
    wheel0 = initial.wheel_rad_s
    n_sc = sigma0.shape[1]
    job = cuda.grid(1)
    if job >= sigma0.shape[0] * n_sc:
        return
    smp = job // n_sc
    i = job % n_sc
    mode = swarm.mode
    spin_rate = swarm.spin_rate
    theta_max = swarm.theta_max
    dt = loop.dt_s
    n_steps = loop.n_steps
    decimate = loop.decimate
    img_every = loop.img_every
    disturbed = loop.disturbed
    ref_table = tables.reference
    torque_table = tables.torque_B_N_m
    sig_err = out.sigma_error
    om_err = out.omega_error
    wheel = out.wheel_speed
    torque = out.wheel_torque
    dcm_BT = out.dcm_BT
    img_omega = out.image_omega
    img_err = out.image_error
    int_limit = gains.int_limit
    I_rw = wheels.I_rw_kgm2
    J_s = wheels.J_s_kgm2
    x = cuda.local.array(9, float64)
    z = cuda.local.array(3, float64)
    ref = cuda.local.array(9, float64)
    u = cuda.local.array(3, float64)
    err = cuda.local.array(6, float64)
    work = cuda.local.array((5, 9), float64)
    L_ext = cuda.local.array(3, float64)
    L_known = cuda.local.array(3, float64)
    for j in range(3):
        z[j] = 0.0
        L_ext[j] = 0.0
        L_known[j] = 0.0
    sigma_RT = swarm.sigma_RT[i]
    dcm_RT = swarm.dcm_RT[i]
    period = swarm.periods_s[i]
    for j in range(3):
        x[j] = sigma0[smp, i, j]
        x[3 + j] = omega0[smp, i, j]
        x[6 + j] = wheel0[smp, i, j]
    ss = x[0] * x[0] + x[1] * x[1] + x[2] * x[2]
    if ss > 1.0:
        for j in range(3):
            x[j] = -x[j] / ss
    mu = 0.0
    mh = 0.0
    c_img = 0
    n_img_done = 0
    c_rec = 0
    r = 0
    for k in range(n_steps + 1):
        t = k * dt
        img = c_img == 0
        if img:
            _camera(x, spin_rate, t, dcm_BT, smp, i, n_img_done)
            for j in range(3):
                img_omega[smp, i, n_img_done, j] = x[3 + j]
        c_img += 1
        if c_img == img_every:
            c_img = 0
        for j in range(3):
            h = abs(J_s[j] * x[6 + j])
            if h > mh:
                mh = h
        rec = c_rec == 0
        if rec:
            for j in range(3):
                wheel[smp, i, r, j] = x[6 + j]
        if mode == TRACK_MODE:
            for j in range(9):
                ref[j] = ref_table[i, k, j]
        else:
            _reference(mode, t, spin_rate, sigma_RT, dcm_RT, theta_max, period, ref)
        if disturbed:
            for j in range(3):
                L_ext[j] = torque_table[i, k, j]
        _control(x, z, ref, gains, wheels, L_known, u, err)
        if img:
            img_err[smp, i, n_img_done] = 4.0 * math.atan(
                math.sqrt(err[0] * err[0] + err[1] * err[1] + err[2] * err[2]))
            n_img_done += 1
        if k < n_steps:
            _rk4(x, u, L_ext, I_rw, J_s, dt, work, x)
            if err[0] * err[0] + err[1] * err[1] + err[2] * err[2] < int_limit * int_limit:
                z[0] += err[0] * dt
                z[1] += err[1] * dt
                z[2] += err[2] * dt
        for j in range(3):
            a = abs(u[j])
            if a > mu:
                mu = a
        if rec:
            for j in range(3):
                sig_err[smp, i, r, j] = err[j]
                om_err[smp, i, r, j] = err[3 + j]
                torque[smp, i, r, j] = u[j]
            r += 1
        c_rec += 1
        if c_rec == decimate:
            c_rec = 0
    out.max_torque[smp, i] = mu
    out.max_momentum[smp, i] = mh


def _table(table: np.ndarray, width: int) -> tuple[np.ndarray, bool]:
    """A step table for the device, and whether it has steps: an empty one ``(N, 0, w)``
    becomes one zero step (never read), as zero-size device arrays are best avoided."""
    if table.shape[1] > 0:
        return np.ascontiguousarray(table, dtype=np.float64), True
    return np.zeros((table.shape[0], 1, width)), False


def simulate_batch_cuda(mode, dcm_RT_all, spin_rate, periods, theta_max, gains, wheels,
                        dt, n_steps, every, initial, tables):
    """:func:`~ideas_hpc.core.attitude.batch.simulate_batch` on the current CUDA device.

    Same parameters and returns (host ``numpy`` arrays, same shapes and order:
    ``sigma_error, omega_error, wheel_speed, wheel_torque, dcm_BT, max_torque,
    max_momentum, image_omega, image_error``); units as there.
    """
    if int(mode) not in (NP_MODE, FOV_MODE, TRACK_MODE):     # as reference_into refuses it
        raise ValueError("simulate_batch_cuda: no reference kernel for this maneuver mode code")
    sigma0, omega0, wheel0 = (np.ascontiguousarray(a, dtype=np.float64) for a in initial)
    n_s, n_sc = sigma0.shape[0], sigma0.shape[1]
    decimate, img_every = int(every[0]), int(every[1])
    n_steps = int(n_steps)
    n_rec = n_steps // decimate + 1
    n_img = n_steps // img_every + 1
    rings = np.ascontiguousarray(dcm_RT_all, dtype=np.float64)
    sigma_RT = np.empty((n_sc, 3))
    for i in range(n_sc):
        sigma_RT[i] = mrp_from_dcm(np.ascontiguousarray(rings[i]))
    ref_table, _ = _table(tables.reference, 9)
    torque_table, disturbed = _table(tables.torque_B_N_m, 3)
    dev = cuda.to_device
    g = type(gains)(*(dev(np.ascontiguousarray(a, dtype=np.float64)) for a in gains[:4]),
                    float(gains.int_limit))
    w = type(wheels)(dev(np.ascontiguousarray(wheels.I_rw_kgm2, dtype=np.float64)),
                     dev(np.ascontiguousarray(wheels.J_s_kgm2, dtype=np.float64)),
                     float(wheels.u_max_Nm), float(wheels.h_max_Nms))
    rec = [cuda.device_array((n_s, n_sc, n_rec, 3)) for _ in range(4)]
    out = Recorded(*rec, cuda.device_array((n_s, n_sc, n_img, 3, 3)),
                   cuda.device_array((n_s, n_sc, n_img, 3)), cuda.device_array((n_s, n_sc, n_img)),
                   cuda.device_array((n_s, n_sc)), cuda.device_array((n_s, n_sc)))
    swarm = SwarmReference(int(mode), dev(rings), dev(sigma_RT), float(spin_rate),
                           dev(np.ascontiguousarray(periods, dtype=np.float64)), float(theta_max))
    loop = LoopSteps(float(dt), n_steps, decimate, img_every, bool(disturbed))
    n_jobs = n_s * n_sc
    threads = THREADS_FEW if n_jobs < MANY_JOBS else THREADS_MANY
    blocks = max(1, -(-n_jobs // threads))
    _flights[blocks, threads](swarm, g, w, loop, Initial(dev(sigma0), dev(omega0), dev(wheel0)),
                              StepTables(dev(ref_table), dev(torque_table)), out)
    cuda.synchronize()
    return tuple(a.copy_to_host() for a in (out.sigma_error, out.omega_error, out.wheel_speed,
                                            out.wheel_torque, out.dcm_BT, out.max_torque,
                                            out.max_momentum, out.image_omega, out.image_error))
