"""Where the closed-loop flights run: ``"cpu"`` (the default and the reference) or ``"cuda"``.

``"cuda"`` runs :func:`~ideas_hpc.core.attitude.batch.simulate_batch`'s loop as the
``numba.cuda`` kernel of :mod:`ideas_hpc.core.attitude.batch_cuda` (same inputs, same
outputs). ``numba.cuda`` is imported only when ``"cuda"`` is asked for, so CPU runs
start as fast as before (docs/gpu.md).
"""

from __future__ import annotations

from ideas_hpc.base.errors import InputError

#: The devices a flight can run on.
DEVICES = ("cpu", "cuda")


def cuda_available() -> bool:
    """``numba.cuda.is_available()`` (True under the simulator, ``NUMBA_ENABLE_CUDASIM=1``)."""
    from numba import cuda

    return bool(cuda.is_available())


def check_device(device: str, field: str = "device") -> str:
    """``device`` if it is one of :data:`DEVICES` and can run here, else an
    :class:`~ideas_hpc.base.errors.InputError` naming ``field``."""
    if device not in DEVICES:
        raise InputError(f"must be one of {', '.join(DEVICES)}, got {device!r}", field=field)
    if device == "cuda" and not cuda_available():
        raise InputError("cuda was asked for but numba.cuda.is_available() is false "
                         "(no CUDA device or driver here); use cpu", field=field)
    return device


def batch_kernel(device: str = "cpu"):
    """The batched closed loop for ``device``: ``simulate_batch`` or its CUDA twin."""
    if device == "cpu":
        from ideas_hpc.core.attitude.batch import simulate_batch
        return simulate_batch
    if device == "cuda":
        from ideas_hpc.core.attitude.batch_cuda import simulate_batch_cuda
        return simulate_batch_cuda
    raise InputError(f"must be one of {', '.join(DEVICES)}, got {device!r}", field="device")
