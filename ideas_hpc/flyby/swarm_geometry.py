"""Spacing of a ring swarm: the closest pair of spacecraft, and the minimum-separation check.

The spacecraft of a ring swarm fly parallel tracks on a cylinder of radius
``d_sep`` about the body's spin axis (SPEC section 3), spacecraft ``i`` at the
swarm angle ``theta_i``. Two tracks are the chord apart,

.. math:: d_{ij} = 2\\, d_{sep} \\sin\\left(\\frac{|\\theta_i - \\theta_j|_{2\\pi}}{2}\\right),

where :math:`|\\cdot|_{2\\pi}` is the angle between them along the ring, in
``[0, pi]``. Along the ring the closest pair is a pair of neighbours once the
angles are sorted (the chord grows with the angle), so the check is O(N log N).
Used by the campaign boundary (``swarm.min_separation_km``) and reusable by
design code that proposes swarms.
"""

from __future__ import annotations

import math

import numpy as np

from ideas_hpc.base.errors import InputError

TWO_PI = 2.0 * math.pi


def closest_pair(theta, d_sep: float) -> tuple[int, int, float]:
    """The two closest spacecraft on the ring and their distance.

    Parameters
    ----------
    theta : (N,) array_like
        Swarm angles, rad (any range; compared modulo 2 pi).
    d_sep : float
        Ring radius, m.

    Returns
    -------
    i, j : int
        Indices into ``theta`` (``i < j``); ``(-1, -1)`` for fewer than two spacecraft.
    distance : float
        Chord between their tracks, m (``inf`` for fewer than two).
    """
    th = np.mod(np.asarray(theta, dtype=np.float64).ravel(), TWO_PI)
    if th.size < 2:
        return -1, -1, math.inf
    order = np.argsort(th, kind="stable")
    s = th[order]
    gaps = np.diff(np.concatenate([s, [s[0] + TWO_PI]]))  # neighbour gaps, wrap included
    k = int(np.argmin(gaps))
    a, b = int(order[k]), int(order[(k + 1) % th.size])
    gap = min(float(gaps[k]), TWO_PI - float(gaps[k]))
    return min(a, b), max(a, b), 2.0 * d_sep * math.sin(0.5 * gap)


def check_separation(theta, d_sep: float, min_separation: float) -> None:
    """Refuse a swarm with two spacecraft closer than ``min_separation`` (m).

    Raises
    ------
    InputError
        Naming ``theta`` (field), the pair, their angles, their distance and
        ``min_separation`` in km (the campaign layer maps both names to its keys).
    """
    i, j, d = closest_pair(theta, d_sep)
    if i < 0 or d >= min_separation:
        return
    th = np.asarray(theta, dtype=np.float64).ravel()
    what = "share the same track" if d == 0.0 else f"are {d / 1e3:.4g} km apart"
    raise InputError(f"spacecraft {i} and {j} (angles {th[i]:.6g} and {th[j]:.6g} rad) {what} on "
                     f"the ring of radius {d_sep / 1e3:.4g} km; the minimum is "
                     f"`min_separation` = {min_separation / 1e3:g}", field="theta")


def min_separation_angle(min_separation: float, d_sep: float) -> float:
    """Smallest angle between two swarm angles whose chord is at least ``min_separation``.

    ``2 asin(s / (2 d_sep))`` (rad), from the chord formula above; ``inf`` when
    ``s > 2 d_sep`` (no two points of the ring are that far apart). Design code
    uses it so that what it proposes passes :func:`check_separation`.
    """
    if min_separation <= 0.0:
        return 0.0
    r = min_separation / (2.0 * d_sep)
    return 2.0 * math.asin(r) if r <= 1.0 else math.inf
