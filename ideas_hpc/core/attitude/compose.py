"""Products of direction cosine matrices in bulk: ``[C T] = [C B][B T]`` per image.

The camera of a Monte Carlo sample is fixed in the body with a misalignment
``[C B]`` (one per spacecraft), so every image's camera DCM is that product.
NumPy's batched ``matmul`` did it before, through OpenBLAS's ``dgemm`` on one
3 x 3 block at a time: per-block dispatch and a fresh 150 MB array per
scenario of the reliability bank. The kernel here forms each entry as
OpenBLAS's FMA kernels do, ``fma(a_2 b_2, fma(a_1 b_1, a_0 b_0))`` (fused
multiply-adds in ``k`` order), so the products, and every coverage row
built on them, are unchanged on machines where NumPy used those kernels;
``tests/test_compose.py`` checks the rounding against exact rational
arithmetic.
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import njit, prange
from numba.core import types
from numba.extending import intrinsic


@intrinsic
def fma(typingctx, a, b, c):
    """``a * b + c`` rounded once (IEEE 754 fusedMultiplyAdd; LLVM ``llvm.fma.f64``)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        fnty = ir.FunctionType(ir.DoubleType(), [ir.DoubleType()] * 3)
        fn = builder.module.declare_intrinsic("llvm.fma", [ir.DoubleType()], fnty)
        return builder.call(fn, args)

    return sig, codegen


@njit(cache=True)
def dot3_fma(a0, a1, a2, b0, b1, b2):
    """``dot(a, b)`` as ``fma(a2, b2, fma(a1, b1, a0 b0))`` (dimensionless)."""
    return fma(a2, b2, fma(a1, b1, a0 * b0))


@njit(cache=True, parallel=True)
def compose_each(dcm_CB, dcm_BT):
    """``[C T]_{i,k} = [C B]_i [B T]_{i,k}`` for every spacecraft ``i`` and image ``k``.

    Parameters
    ----------
    dcm_CB : (N, 3, 3) float64
        One fixed DCM per spacecraft (e.g. the camera misalignment).
    dcm_BT : (N, K, 3, 3) float64, C-contiguous
        DCMs per spacecraft and image.

    Returns
    -------
    dcm_CT : (N, K, 3, 3) float64
        Each entry ``sum_m C[r, m] B[m, c]`` by :func:`dot3_fma`.
    """
    n, k = dcm_BT.shape[0], dcm_BT.shape[1]
    out = np.empty_like(dcm_BT)
    for job in prange(n * k):
        i = job // k
        j = job % k
        for r in range(3):
            for c in range(3):
                out[i, j, r, c] = dot3_fma(dcm_CB[i, r, 0], dcm_CB[i, r, 1], dcm_CB[i, r, 2],
                                           dcm_BT[i, j, 0, c], dcm_BT[i, j, 1, c],
                                           dcm_BT[i, j, 2, c])
    return out
