"""Every shipped campaign runs as shipped (issue 22): on the built-in ellipsoid with
only the sizes that make it slow made small (never design.n_max nor the requirement),
and, marked slow, on eros001708 exactly as shipped."""

from __future__ import annotations

from pathlib import Path

import pytest
import xarray as xr

from ideas_hpc.report.write import write_report
from ideas_hpc.campaign.run import run_file
from ideas_hpc.campaign.schema.campaign_tables import load
from small_stores import run_once

CAMPAIGNS = Path(__file__).resolve().parent.parent / "campaigns"
FILES = sorted(p.name for p in CAMPAIGNS.glob("*.toml"))

#: file -> overrides of sizes only (samples, population, generations, grid step, the
#: solver's time budget)
SMALL = {
    # the main job's kind: its scenario bank (scenarios x candidates closed-loop flights)
    # grows with the grid, so 12 candidates (30 deg; about a fifth of the run's CPU saved
    # against 12 deg; tests/test_campaign_failures.py designs this file on the ellipsoid
    # at 30 deg too); a run (with its step-up) and its report is what is checked, and 100
    # scenarios / samples are the fewest that resolve its p = 0.9
    "eros-design.toml": ["design.scenarios=100", "design.verify_samples=100",
                         "design.angle_step_deg=30.0"],
    "eros-design-nominal.toml": ["design.verify_samples=2", "design.angle_step_deg=3.0"],
    "eros-design-quick.toml": ["design.angle_step_deg=12.0"],
    "eros-fast-encounter.toml": ["design.verify_samples=2", "design.angle_step_deg=6.0"],
    "eros-fast-encounter-flyby.toml": [],
    "eros-fast-encounter-nav.toml": ["design.verify_samples=2", "design.angle_step_deg=6.0"],
    "eros-flyby.toml": [],
    "eros-fov-ga.toml": ["design.population=6", "design.generations=2"],
    "eros-monte-carlo.toml": ["monte_carlo.samples=2", "run.chunk_size=1"],
    "eros-nadir-ga.toml": ["design.population=8", "design.generations=3",
                           "design.angle_step_deg=5.0"],
    "eros-nadir.toml": ["design.verify_samples=2", "design.angle_step_deg=3.0"],
    "eros-pareto.toml": ["design.population=8", "design.generations=3",
                         "design.angle_step_deg=5.0"],
    "eros-stereo-design.toml": ["design.verify_samples=2", "design.angle_step_deg=12.0",
                                "design.time_limit_s=5"],
}
#: Files whose body comes from their [target] prior (never flown on another body), each run
#: small by a docs example (CI ran them here too, a second time: 2 minutes of its budget):
#: the main job by the README (and as shipped, with its report, by tests/test_main_job.py),
#: the coarse Eros-class design by docs/study.md (with its study and report; also
#: tests/test_study.py, tests/test_design_distance.py).
PRIOR_BODY = {"eros-class-flyby.toml": "docs/study.md", "fast-flyby-design.toml": "README.md"}
FORBIDDEN = ("design.n_max", "design.eps_tol_pct", "coverage.", "design.failures_tolerated")


def test_every_campaign_file_is_listed_and_only_sizes_change():
    assert sorted([*SMALL, *PRIOR_BODY]) == FILES and not set(SMALL) & set(PRIOR_BODY)
    assert not [s for sets in SMALL.values() for s in sets if s.startswith(FORBIDDEN)]


def test_prior_body_files_run_in_their_docs_examples():
    from test_doc_examples import examples

    for name, page in PRIOR_BODY.items():
        runs = [ex for ex in examples() if ex.page == page and not ex.skip
                and any(c[1:3] == ["run", f"campaigns/{name}"] for c in ex.commands)]
        assert runs, f"no example of {page} runs campaigns/{name}"
        # the docs run sizes only, as SMALL does here
        sets = [a for ex in runs for c in ex.commands for a in c if "=" in a]
        sets += [o for ex in runs for o in ex.overrides if "=" in o]
        assert not [s for s in sets if s.startswith(FORBIDDEN)], (name, sets)


def _run(name: str, sets: list, out: Path, shared_root: Path | None = None) -> xr.Dataset:
    workers = 1 if name == "eros-monte-carlo.toml" else 0
    if shared_root is not None:   # a run other tests of the session may read too
        store = run_once(name, sets, workers, shared_root)
    else:
        store = run_file(CAMPAIGNS / name, out=out / "s.zarr", overrides=sets,
                         workers=workers, progress=False)
    summary = write_report(store, out / "report").read_text()
    assert "body: " in summary.splitlines()[1]
    return xr.open_zarr(store)


@pytest.mark.parametrize("name", sorted(SMALL))
def test_campaign_runs_on_the_ellipsoid(name, tmp_path):
    ds = _run(name, ['body.name="ellipsoid"'] + SMALL[name], tmp_path)
    assert ds.attrs["body"] == "ellipsoid"


#: The main job's scenario bank (256 x 720 closed-loop flights, several minutes on 2
#: cores) is the one size CI cannot afford as shipped: its eros001708 run uses the
#: smallest bank its requirement allows (10 / (1 - p) = 100 scenarios and samples).
AS_SHIPPED = ['body.name="eros001708"']
EROS_SIZES = {"eros-design.toml": ["design.scenarios=100", "design.verify_samples=100"]}

#: Files that a docs example already runs as shipped on the real Eros (body "eros" is
#: eros001708 wherever the data is, which .ci/run requires): the slow run does not fly
#: them a second time here (each is a minute or more on 2 cores); the test below keeps
#: those examples in place.
RUN_BY_DOCS = {"eros-design-quick.toml": "README.md",
               "eros-fast-encounter.toml": "docs/guide/science.md"}


def test_files_left_to_the_docs_are_run_there_as_shipped():
    from test_doc_examples import examples

    for name, page in RUN_BY_DOCS.items():
        shipped = [ex for ex in examples() if ex.page == page and not ex.skip
                   and not ex.overrides
                   and any(c[1:3] == ["run", f"campaigns/{name}"] and "--set" not in c
                           for c in ex.commands)]
        assert shipped, f"no example of {page} runs campaigns/{name} as shipped"
        assert load(CAMPAIGNS / name).config.body.name == "eros"


@pytest.mark.slow
@pytest.mark.parametrize("name", [f for f in FILES
                                  if f not in RUN_BY_DOCS and f not in PRIOR_BODY])
def test_campaign_runs_on_eros001708_as_shipped(name, tmp_path, tmp_path_factory, eros1708):
    # shared with tests/test_ga_optimum.py: its shipped seed is one of the GA's seeds
    ds = _run(name, AS_SHIPPED + EROS_SIZES.get(name, []), tmp_path,
              shared_root=tmp_path_factory.getbasetemp())
    assert ds.attrs["shape_model"] == "eros001708"
