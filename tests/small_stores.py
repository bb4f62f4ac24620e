"""One small store of every kind on the built-in ellipsoid, built once per test session.

Shared by the store-attribute walk (tests/test_store_attrs.py), the figure tests
and the HTML report test: ``small_store(kind, root)`` runs the shipped campaign
with sizes made small (never the requirement) and returns the store path.
"""

from __future__ import annotations

from pathlib import Path

from ideas_hpc.campaign.run import run_file

CAMPAIGNS = Path(__file__).resolve().parent.parent / "campaigns"
SHORT_FLIGHT = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3",
                "flyby.z_stop_km=3"]

#: kind -> (campaign file, overrides, workers)
KINDS = {
    "flyby": ("eros-flyby.toml", SHORT_FLIGHT + ["attitude.decimate=10"], 0),
    "design-exact": ("eros-nadir.toml", SHORT_FLIGHT + [
        "design.angle_step_deg=10", "design.n_max=6", "design.verify_samples=4",
        "design.failures_tolerated=1"], 1),
    "design-ga": ("eros-nadir-ga.toml", SHORT_FLIGHT + [
        "design.angle_step_rad=0.2", "design.population=8", "design.generations=3",
        "design.n_max=4"], 0),
    "design-fov": ("eros-fov-ga.toml", SHORT_FLIGHT + [
        "design.population=6", "design.generations=2", "swarm.angles_rad=[0.2, 2.4, 4.0]",
        "design.p_max_min=2.0"], 0),
    "design-pareto": ("eros-pareto.toml", SHORT_FLIGHT + [
        "design.angle_step_deg=10", "design.population=8", "design.generations=3"], 0),
    # the success-probability designer (the main job's kind), on the smoke campaign made
    # smaller still: p = 0.5 needs only 20 scenarios and 20 validation samples
    "design-reliability": ("eros-design-quick.toml", SHORT_FLIGHT + [
        "design.angle_step_deg=10", "design.n_max=6", "design.success_probability=0.5",
        "design.scenarios=20", "design.verify_samples=20", 'attitude.mode="ideal"'], 0),
    "monte-carlo": ("eros-monte-carlo.toml", SHORT_FLIGHT + [
        "attitude.decimate=10", "monte_carlo.samples=4", "run.chunk_size=2"], 1),
}

_BUILT: dict[str, Path] = {}


def small_store(kind: str, root: Path) -> Path:
    """The store of ``kind`` (a key of :data:`KINDS`), built under ``root`` on first use."""
    if kind not in _BUILT:
        campaign, sets, workers = KINDS[kind]
        _BUILT[kind] = run_file(CAMPAIGNS / campaign, out=Path(root) / f"{kind}.zarr",
                                overrides=sets, workers=workers, progress=False)
    return _BUILT[kind]


_RUNS: dict[tuple, Path] = {}


def run_once(campaign: str, sets: list[str], workers: int, root: Path) -> Path:
    """The store of ``campaign`` with ``sets`` (in this order) and ``workers``, run under
    ``root`` on first use: tests that check different things of one run share it (the
    as-shipped GA campaign on eros001708 is both a shipped campaign and a GA seed)."""
    key = (campaign, tuple(sets), workers)
    if key not in _RUNS:
        out = Path(root) / f"run{len(_RUNS)}-{Path(campaign).stem}.zarr"
        _RUNS[key] = run_file(CAMPAIGNS / campaign, out=out, overrides=list(sets),
                              workers=workers, progress=False)
    return _RUNS[key]
