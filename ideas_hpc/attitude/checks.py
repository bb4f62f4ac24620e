"""Input checks shared by the attitude boundary layer: each raises
:class:`~ideas_hpc.base.errors.InputError` naming the field."""

from __future__ import annotations

import numpy as np

from ideas_hpc.base.errors import InputError


def vec3(value, name):
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"must be a number or 3 numbers, got {value!r}", field=name) from None
    if a.ndim == 0:
        a = np.full(3, float(a))
    if a.shape != (3,):
        raise InputError(f"must be a number or 3 numbers, got {value!r}", field=name)
    if not np.all(np.isfinite(a)) or np.any(a < 0):
        raise InputError(f"gains must be finite and non-negative, got {value!r}", field=name)
    return tuple(float(v) for v in a)


def check_theta(theta):
    th = np.atleast_1d(np.asarray(theta, dtype=np.float64))
    if th.ndim != 1 or th.size == 0 or not np.all(np.isfinite(th)):
        raise InputError("must be a non-empty 1-D array of finite angles in rad", field="theta")
    return th


def steps(total, dt, name):
    k = int(round(total / dt))
    if k < 1 or abs(k * dt - total) > 1e-9 * max(total, dt):
        raise InputError(f"the step dt = {dt} s must divide {name} = {total} s", field="dt")
    return k


def init_array(a, name, n):
    arr = np.asarray(a, dtype=np.float64)
    if arr.ndim == 2:
        arr = arr[None]
    if arr.ndim != 3 or arr.shape[1:] != (n, 3):
        raise InputError(f"must have shape (S, {n}, 3), got {np.shape(a)}", field=name)
    if not np.all(np.isfinite(arr)):
        raise InputError("initial state is not finite", field=name)
    return np.ascontiguousarray(arr)
