"""Benchmark: where a success-probability design's time goes, phase by phase, per scenario.

Runs a design campaign in this process (``--workers 0``, the kernels on every
core) with timers wrapped around the functions each phase goes through, and
prints the exclusive seconds of each phase (a phase's time less that of the
phases it calls) inside each section of the job:

phases (what the time is spent on)
    world draw (a scenario's dispersion draws and, with a target prior, its drawn
    shape, pole and spin: ``draw_world``, ``scenario_world``, ``drawn_world``); targeting
    (``flyby.flight.target``: the candidates' start states on the nominal model); nominal
    proofs (``RowEngine.prepare``: the nominal flight's witnesses and windows, once per
    bank of the nominal world); statics (what is
    built once per world and kept: ``flyby.world.cached_static``, the BVH and
    lighting records of ``mapping.coverage``); flight and attitude
    (``flyby.views.flight_views``: the orbits and the closed loop to the cameras
    at the images); visibility and rows (the row kernels: proofs and time trees
    on the nominal world, the full strict/quality kernels on a drawn one); design
    solve (``design.api.minimize``: HiGHS and the screens); the rest (Python, the
    store). Statics include each world's reference area (``reference_areas``: the
    surface lit at closest approach, with ``coverage_reference = "lit_at_tca"``).
sections (when)
    candidate masks, scenario bank, held-out and validation flights, the rest
    (design, certificate, final flyby, store).

Per scenario: the scenario bank's phases divided by its scenario count (each
scenario flies every candidate). The job runs twice, the first untimed in another
process (a warm Numba cache: compilation is not a phase, loading a kernel is;
``--once`` skips it when the cache is warm). Numbers unchanged: the wrappers only
read the clock.

Workloads (``--bank``): ``drawn`` is ``campaigns/eros-class-flyby.toml`` as
written (coarse: 45 candidates, 20 drawn worlds, 642 vertices); ``paper`` is the
main job's bank (``campaigns/eros-design.toml``: eros001708, 720 candidates,
closed-loop attitude) cut to 20 scenarios at p = 0.5 with 20 held-out and 20
validation samples. Last line: ``phases: <bank> per scenario <s> s: ...``.

Usage: ``python benchmarks/bench_phases.py [--bank drawn|paper|both] [--once]``.
"""

from __future__ import annotations

import argparse
import functools
import os
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

WORKLOADS = {
    "drawn": ("eros-class-flyby.toml", []),
    "paper": ("eros-design.toml", ["design.success_probability=0.5", "design.scenarios=20",
                                   "design.holdout_scenarios=20", "design.verify_samples=20",
                                   "design.demonstrate=false"]),
}
PHASES = ("world draw", "targeting", "nominal proofs", "statics", "flight and attitude", "visibility and rows",
          "design solve")
SECTIONS = ("candidate masks", "scenario bank", "held-out and validation flights")


class Clock:
    """Exclusive phase times per section (a stack of running phases)."""

    def __init__(self):
        self.t = defaultdict(float)      # (section, phase) -> s
        self.stack: list = []            # [phase, start, child seconds]
        self.section = "rest"
        self.scenarios = 0

    def phase(self, name, fn):
        @functools.wraps(fn)
        def timed(*a, **k):
            self.stack.append([name, time.perf_counter(), 0.0])
            try:
                return fn(*a, **k)
            finally:
                ph, t0, child = self.stack.pop()
                dt = time.perf_counter() - t0
                self.t[(self.section, ph)] += dt - child
                if self.stack:
                    self.stack[-1][2] += dt
        return timed

    def in_section(self, name, fn):
        @functools.wraps(fn)
        def timed(*a, **k):
            outer, self.section = self.section, name
            try:
                return self.phase("rest", fn)(*a, **k)
            finally:
                self.section = outer
        return timed


def _replace_everywhere(orig, new) -> int:
    """Point every loaded ``ideas_hpc`` module's name for ``orig`` at ``new``."""
    n = 0
    for name, mod in list(sys.modules.items()):
        # not inside the kernel modules: a kernel that calls another by its global name
        # would compile against the wrapper
        if mod is None or not name.startswith("ideas_hpc") or name.startswith("ideas_hpc.core"):
            continue
        for attr, val in list(vars(mod).items()):
            if val is orig:
                setattr(mod, attr, new)
                n += 1
    return n


def instrument(clock: Clock) -> None:
    import ideas_hpc.campaign.run  # noqa: F401  (every module the job uses, loaded)
    import ideas_hpc.campaign.design_reliability  # noqa: F401
    from ideas_hpc.core.mapping import coverage as kcov, quality_masks as kq
    from ideas_hpc.core.mapping import scenario_rows as krows
    from ideas_hpc.design import api, bank
    from ideas_hpc.flyby import flight, views, world, target_world
    from ideas_hpc.mapping import coverage as mcov
    from ideas_hpc.montecarlo import scenarios

    from ideas_hpc.flyby import reference_area
    from ideas_hpc.mapping import world_rows as wrows   # the world bank (issue 43)

    phases = {"world draw": [scenarios.draw_world, target_world.scenario_world,
                             target_world.drawn_world],
              "targeting": [flight.target],
              "statics": [world.cached_static, mcov._strict_args, mcov._mesh,
                          reference_area.reference_areas, wrows.world_statics],
              "flight and attitude": [views.flight_views],
              "visibility and rows": [kcov.first_image_by_spacecraft, wrows.rows_of_world],
              "design solve": [api.minimize]}
    for name, fns in phases.items():
        for f in fns:
            _replace_everywhere(f, clock.phase(name, f))
    sections = {"candidate masks": [bank.build_bank],
                "scenario bank": [scenarios.build_scenario_bank],
                "held-out and validation flights": [scenarios.fly_members,
                                                    scenarios.fly_members_seen]}
    for name, fns in sections.items():
        for f in fns:
            _replace_everywhere(f, clock.in_section(name, f))
    # the bank's proofs on the nominal flight, made once per bank (a method: on its class)
    from ideas_hpc.montecarlo.scenario_rows import RowEngine

    _SAVED[(RowEngine, "prepare")] = RowEngine.prepare
    RowEngine.prepare = clock.phase("nominal proofs", RowEngine.prepare)
    # the row kernels the boundary reads as module attributes (``_k.perturbed_rows``), which
    # no kernel calls: wrapped in their own modules (restored by uninstrument)
    for mod, names in ((krows, ["perturbed_rows"]),
                       (kcov, ["observed_by_spacecraft", "coverage_vertices"]),
                       (kq, ["quality_by_spacecraft"])):
        for n in names:
            _SAVED[(mod, n)] = getattr(mod, n)
            setattr(mod, n, clock.phase("visibility and rows", getattr(mod, n)))


def run_job(campaign: Path, sets: list, out: Path) -> float:
    from ideas_hpc.cli import main

    argv = ["run", str(campaign), "--out", str(out), "--workers", "0", "--no-progress"]
    for s in sets:
        argv += ["--set", s]
    t0 = time.perf_counter()
    rc = main(argv)
    if rc:
        sys.exit(f"ideas-hpc {' '.join(argv)} failed ({rc})")
    return time.perf_counter() - t0


def measure(key: str, once: bool) -> tuple[Clock, float, int]:
    name, sets = WORKLOADS[key]
    campaign = ROOT / "campaigns" / name
    with tempfile.TemporaryDirectory(prefix="bench-phases-") as tmp:
        if not once:    # compile, untimed, in another process: this one draws its worlds afresh
            cmd = [sys.executable, "-m", "ideas_hpc.cli", "run", str(campaign), "--out",
                   str(Path(tmp) / "warm.zarr"), "--workers", "0", "--no-progress"]
            for s in sets:
                cmd += ["--set", s]
            subprocess.run(cmd, check=True, capture_output=True)
        clock = Clock()
        instrument(clock)
        try:
            wall = run_job(campaign, sets, Path(tmp) / "timed.zarr")
        finally:
            uninstrument()
    from ideas_hpc.campaign.schema.campaign_tables import load

    return clock, wall, int(load(campaign, sets).config.design.scenarios)


_SAVED: dict = {}


def uninstrument() -> None:
    """Undo :func:`instrument` (every module's names back to the originals)."""
    for (mod, n), f in _SAVED.items():
        setattr(mod, n, f)
    _SAVED.clear()
    for name, mod in list(sys.modules.items()):
        if mod is None or not name.startswith("ideas_hpc"):
            continue
        for attr, val in list(vars(mod).items()):
            orig = val
            while hasattr(orig, "__wrapped__") and getattr(orig, "__module__", "") == __name__:
                orig = orig.__wrapped__
            if orig is not val:
                setattr(mod, attr, orig)


def report(key: str, clock: Clock, wall: float, n: int) -> str:
    sections = list(SECTIONS) + ["rest"]
    cols = list(PHASES) + ["rest"]
    print(f"\n{key} bank ({WORKLOADS[key][0]} {' '.join(WORKLOADS[key][1])}): job {wall:.1f} s "
          f"in this process, {n} scenarios; exclusive seconds")
    print("| section | " + " | ".join(cols) + " | total |")
    print("|---" * (len(cols) + 2) + "|")
    for s in sections:
        row = [clock.t.get((s, p), 0.0) for p in cols]
        print(f"| {s} | " + " | ".join(f"{x:.2f}" for x in row) + f" | {sum(row):.2f} |")
    print(f"(outside every phase and section: targeting, the final flyby, the store, Python: "
          f"{wall - sum(clock.t.values()):.2f} s)")
    bank_t = {p: clock.t.get(("scenario bank", p), 0.0) for p in cols}
    per = sum(bank_t.values()) / max(n, 1)
    parts = ", ".join(f"{p} {bank_t[p] / max(n, 1):.3f} s ({100 * bank_t[p] / max(sum(bank_t.values()), 1e-12):.0f} %)"
                      for p in cols)
    print(f"per scenario of the bank: {per:.3f} s: {parts}")
    return f"{key} per scenario {per:.3f} s: " + ", ".join(
        f"{p} {100 * bank_t[p] / max(sum(bank_t.values()), 1e-12):.0f} %" for p in cols)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bank", choices=("drawn", "paper", "both"), default="both")
    ap.add_argument("--once", action="store_true", help="no untimed first run (warm cache)")
    a = ap.parse_args(argv)
    os.environ.setdefault("MPLBACKEND", "Agg")
    heads = []
    for key in (("drawn", "paper") if a.bank == "both" else (a.bank,)):
        clock, wall, n = measure(key, a.once)
        heads.append(report(key, clock, wall, n))
    print(f"machine load {os.getloadavg()[0]:.1f} (a shared machine's figures move with it)")
    print("phases: " + "; ".join(heads))


if __name__ == "__main__":
    main()
