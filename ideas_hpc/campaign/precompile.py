"""Cold start: compile a job's later kernels in a second process while this one works.

On an empty Numba cache a job compiles its kernels one after the other, in
the order it first calls them, on one core: a design job compiles the
targeting kernels, then the candidate-mask kernel, then (for its Monte Carlo
verification and the final flyby) the open-loop propagation and the coverage
kernel. :func:`start` launches one helper process that compiles the
mask, coverage and propagation kernels with the job's own argument types (tiny
inputs made from the job's :class:`~ideas_hpc.flyby.flight.FlybySetup`, so the very
specialisations the job needs) and writes them to the cache; when the job
reaches them it loads them instead of compiling. Each kernel is still compiled
once (whichever process gets there first; the helper's order puts the
targeting kernels last so that the two processes do not duplicate them).

Nothing is started when the cache already holds these kernels. The helper's
failure changes nothing but the time: the job compiles what it does not find.

Opt-in (``IDEAS_HPC_PRECOMPILE=1``): it needs a second idle core. Measured
on the shared 2-core VM under load 6-9 from other users
(``benchmarks/bench_startup.py --helper``, same run), the main job's cold
start took 131.6 s with the helper and 103.9 s without: the helper only
competes with the job there. Measure on a quiet machine before turning it on
by default.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import tempfile

import numpy as np

from ideas_hpc.core.mapping import coverage as _cov
from ideas_hpc.core.dynamics import targeting as _tgt


def cache_is_warm() -> bool:
    """True when the cache has an index for the coverage and propagation kernels."""
    try:
        return all(os.path.exists(f._cache._cache_file._index_path)
                   for f in (_cov.coverage_vertices, _cov.observed_by_spacecraft,
                             _tgt.propagate_batch))
    except AttributeError:  # a Numba without these internals: assume warm
        return True


def warm_kernels(setup) -> None:
    """Call the mask, coverage and propagation kernels once on tiny inputs of the job's types."""
    from ideas_hpc.mapping.coverage import compute_coverage, observed_per_spacecraft, quality_per_spacecraft
    from ideas_hpc.dynamics.trajectory import propagate_swarm

    shape = setup.body.shape
    t = np.ascontiguousarray(setup.image_times[:2])
    r = np.zeros((1, t.size, 3))
    r[..., 0] = setup.d_sep_m
    dcm = np.ascontiguousarray(np.broadcast_to(np.eye(3), (1, t.size, 3, 3)))
    opts = setup.coverage
    sun = setup.sun_T(t) if opts.needs_sun else None
    args = (shape, r, dcm, setup.eta_rad, setup.near_m, setup.far_m)
    if opts.requirement:
        quality_per_spacecraft(shape, r, dcm, t, setup.eta_rad, setup.near_m, setup.far_m,
                               options=opts, sun_T=sun)
    else:
        observed_per_spacecraft(*args, options=opts, sun_T=sun)
    compute_coverage(shape, r, dcm, t, setup.eta_rad, setup.near_m, setup.far_m, options=opts,
                     sun_T=sun, active=np.ones(1, dtype=np.bool_), counts=False)
    r0 = np.array([[setup.d_sep_m, 0.0, setup.z_start_m]])
    v0 = np.array([[0.0, 0.0, (setup.z_stop_m - setup.z_start_m) / (setup.tf_s - setup.t0_s)]])
    propagate_swarm(setup.body, r0, v0, setup.t0_s, setup.t0_s + 2 * setup.dt_s,
                    force_model=setup.force_model, dt_sample=setup.dt_s, views=True)


class Helper:
    """A running helper process (:func:`start`); :meth:`close` waits for it."""

    def __init__(self, proc: subprocess.Popen, path: str):
        self.proc = proc
        self._path = path

    def close(self, timeout: float = 600.0) -> None:
        try:
            self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        finally:
            if os.path.exists(self._path):
                os.unlink(self._path)

    def __enter__(self) -> "Helper":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def start(setup) -> Helper | None:
    """Start the helper for ``setup`` when asked (``IDEAS_HPC_PRECOMPILE=1``) and the
    cache is cold; None otherwise."""
    if os.environ.get("IDEAS_HPC_PRECOMPILE", "") != "1" or cache_is_warm():
        return None
    fd, path = tempfile.mkstemp(prefix="ideas-hpc-precompile-", suffix=".pkl")
    with os.fdopen(fd, "wb") as fh:
        pickle.dump(setup, fh)
    proc = subprocess.Popen([sys.executable, "-m", "ideas_hpc.campaign.precompile", path],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            stdin=subprocess.DEVNULL)
    return Helper(proc, path)


if __name__ == "__main__":  # the helper process
    with open(sys.argv[1], "rb") as fh:
        warm_kernels(pickle.load(fh))
