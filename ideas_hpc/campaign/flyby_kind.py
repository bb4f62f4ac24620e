"""Kind ``flyby``: one flyby of ``swarm.angles_rad`` (SPEC sections 2-6, store section 9)."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import xarray as xr

from ideas_hpc.base.progress import result
from ideas_hpc.flyby.encounter import pointing_profile
from ideas_hpc.flyby.flight import fly
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.campaign import datasets
from ideas_hpc.engine.variables import with_attrs
from ideas_hpc.campaign.schema.campaign_tables import Campaign


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def run_flyby(c: Campaign, out: Path, **_) -> xr.Dataset:
    """Kind ``flyby``: one flyby of ``swarm.angles_rad``."""
    setup = setup_from_campaign(c)
    _log(f"body: {setup.body.note}")
    sw = c.config.swarm
    periods = setup.maneuver.swarm_periods(sw.sweep_periods_s)
    t = time.perf_counter()
    res = fly(setup, sw.angles_rad, periods)
    result(f"flyby: {len(sw.angles_rad)} spacecraft, coverage {100 * res.coverage.coverage:.3f} % "
           f"(area), {100 * res.coverage.coverage_count:.3f} % (vertices) in "
           f"{time.perf_counter() - t:.1f} s")
    ds = datasets.flyby_dataset(setup, res)
    ds.attrs.update(datasets.base_attrs(c, setup))
    point = pointing_profile(setup, sw.angles_rad, periods, res.r_img_T)
    line = point.pop("summary")   # a wheel-limit WARNING is a warning: stderr, like the logs
    (_log if line.startswith("WARNING") else result)(line)
    for name, v in point.items():
        ds[name] = (("spacecraft",), v)
    return with_attrs(ds)
