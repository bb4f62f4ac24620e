"""Bulk DCM products (ideas_hpc.core.attitude.compose) against exact rational arithmetic.

Each entry must be the fused multiply-add chain ``fma(a2, b2, fma(a1, b1, a0 b0))``
rounded as IEEE 754 says: ``float(Fraction)`` rounds an exact rational to the
nearest double (ties to even), so the chain computed in fractions is the oracle.
The product must also agree with ``numpy.matmul`` to rounding.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from ideas_hpc.core.attitude.compose import compose_each
from ideas_hpc.flyby.camera import misaligned


def _fma_exact(a, b, c):
    return float(Fraction(a) * Fraction(b) + Fraction(c))


def _rotations(rng, n):
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    w, x, y, z = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], 1)


def test_each_entry_is_the_fused_chain_rounded_exactly():
    rng = np.random.default_rng(3)
    a = _rotations(rng, 4)
    b = _rotations(rng, 4 * 6).reshape(4, 6, 3, 3)
    out = compose_each(a, b)
    for i in range(4):
        for k in range(6):
            for r in range(3):
                for c in range(3):
                    p0 = a[i, r, 0] * b[i, k, 0, c]
                    want = _fma_exact(a[i, r, 2], b[i, k, 2, c],
                                      _fma_exact(a[i, r, 1], b[i, k, 1, c], p0))
                    assert out[i, k, r, c] == want


def test_misaligned_agrees_with_numpy_matmul_and_passes_none_through():
    rng = np.random.default_rng(4)
    a = _rotations(rng, 5)
    b = _rotations(rng, 5 * 40).reshape(5, 40, 3, 3)
    np.testing.assert_allclose(misaligned(b, a), np.matmul(a[:, None], b), rtol=0, atol=4e-16)
    assert misaligned(b, None) is b
