"""Cold start: compile a job's later kernels in a second process while this one works.

On an empty Numba cache a job compiles its kernels one after the other, in
the order it first calls them: a design job compiles the targeting kernels,
then the candidate-mask kernel, then (in its scenario bank's first chunks, or
its Monte Carlo verification and final flyby) the flight, row and coverage
kernels. :func:`start` launches one helper process that compiles the later
phases' kernels with the job's own argument types (tiny inputs made from the
job's :class:`~ideas_hpc.flyby.flight.FlybySetup`, so the very
specialisations the job needs) and writes them to the cache while the job
computes its masks: the scenario bank's (one scenario of two candidates,
:func:`~ideas_hpc.montecarlo.scenarios.warm_rows`; a success-probability
design only), then the mask, coverage and propagation kernels. When the job or
its workers reach a kernel they load it, or, while the helper still compiles
it, wait for it and then load it (:mod:`ideas_hpc.base.compile_once`): each
kernel is compiled once, by whichever process gets there first.

Nothing is started when the cache already holds these kernels, or on one CPU.
The helper's failure changes nothing but the time: the job compiles what it
does not find. ``IDEAS_HPC_PRECOMPILE=0`` turns it off, ``1`` starts it
whenever the cache is cold (also on one CPU).

History: opt-in until issue 43, measured on the shared 2-core VM under load
6-9 (``benchmarks/bench_startup.py --helper``) at 131.6 s with the helper and
103.9 s without, when the helper and the job could compile the same kernel
twice; with the per-kernel lock they cannot.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import tempfile

import numpy as np

from ideas_hpc.base.compile_once import lock_path
from ideas_hpc.core.mapping import coverage as _cov
from ideas_hpc.core.mapping import quality_masks as _qmask
from ideas_hpc.core.mapping import scenario_rows as _rows
from ideas_hpc.core.dynamics import targeting as _tgt


def cache_is_warm(bank: bool = False, setup=None) -> bool:
    """True when the cache has an index for the first kernels the helper would compile:
    the coverage and propagation kernels, or with ``bank`` the scenario bank's row
    kernel (the proofs' on the nominal world, the full strict or quality kernel on a
    drawn world or under a ``[coverage]`` requirement). Only kernels the job itself
    calls: a helper stopped at the end of a short job must not start again on every
    later run for kernels no run needs."""
    if not bank:
        kernels = [_cov.coverage_vertices, _cov.observed_by_spacecraft, _tgt.propagate_batch]
    elif setup is not None and setup.coverage.requirement:
        kernels = [_qmask.quality_by_spacecraft]
    elif setup is not None and getattr(setup, "target", None) is not None:
        kernels = [_cov.observed_by_spacecraft]
    else:
        kernels = [_rows.perturbed_rows]
    paths = [lock_path(f) for f in kernels]
    # a Numba without these internals: assume warm
    return any(p is None for p in paths) or all(os.path.exists(p[:-5]) for p in paths)


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

    def close(self) -> None:
        """The job is done: what the helper has not compiled yet nobody waits for, so it
        stops (a kernel it was writing is written whole or not at all: Numba replaces
        cache files atomically, and its lock goes with it)."""
        try:
            if self.proc.poll() is None:
                self.proc.terminate()
            self.proc.wait()
        finally:
            if os.path.exists(self._path):
                os.unlink(self._path)

    def __enter__(self) -> "Helper":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def warm_bank(setup, mc, seed: int) -> None:
    """The scenario bank's kernels (:func:`~ideas_hpc.montecarlo.scenarios.warm_rows`)."""
    from ideas_hpc.montecarlo.scenarios import warm_rows

    warm_rows(setup, mc, seed)


def warm_all(setup, bank=None) -> None:
    """The helper's work: the bank's kernels first (``bank``: ``(mc, seed)`` of a
    success-probability design), then :func:`warm_kernels`."""
    if bank is not None:
        warm_bank(setup, *bank)
    warm_kernels(setup)


def wanted(bank: bool, setup=None) -> bool:
    """Whether to start the helper: ``IDEAS_HPC_PRECOMPILE`` (``0`` never, ``1`` on a
    cold cache), by default on a cold cache with a second CPU (:func:`cache_is_warm`)."""
    mode = os.environ.get("IDEAS_HPC_PRECOMPILE", "")
    if mode == "0" or (mode != "1" and (os.cpu_count() or 1) < 2):
        return False
    return not cache_is_warm(bank, setup)


def start(setup, campaign=None) -> Helper | None:
    """Start the helper for ``setup`` (and, for a success-probability ``campaign``, its
    scenario bank) when :func:`wanted`; None otherwise."""
    d = getattr(getattr(campaign, "config", None), "design", None)
    bank = None
    if getattr(d, "success_probability", None) is not None:
        bank = (campaign.config.monte_carlo, int(campaign.config.seed))
    if not wanted(bank is not None, setup):
        return None
    fd, path = tempfile.mkstemp(prefix="ideas-hpc-precompile-", suffix=".pkl")
    with os.fdopen(fd, "wb") as fh:
        pickle.dump((setup, bank), fh)
    proc = subprocess.Popen([sys.executable, "-m", "ideas_hpc.campaign.precompile", path],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            stdin=subprocess.DEVNULL)
    return Helper(proc, path)


if __name__ == "__main__":  # the helper process
    with open(sys.argv[1], "rb") as fh:
        warm_all(*pickle.load(fh))
