"""Benchmark: the paper-sized NP GA (population 100, 115 generations) on Eros.

Runs ``campaigns/eros-nadir-ga.toml`` end to end (``ideas-hpc run``: sizing,
candidate masks in chunks over 2 local dask workers, pygad with whole-
population evaluation, the final flyby of the best swarm, the store) twice:
with ``ideal`` attitude and with ``simulated`` (closed-loop) attitude.

For scale it also times the honest naive evaluation: one full flyby
(:func:`ideas_hpc.flyby.flight.fly`, compiled kernels, ideal attitude) per
individual, as a GA without the per-spacecraft mask bank would do, and
extrapolates it to the same number of evaluations.

Prints designs evaluated per second; last line
``ga: <S> s for the paper-sized NP GA (simulated attitude)``.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from ideas_hpc.campaign.run import run_file  # noqa: E402
from ideas_hpc.campaign.schema.campaign_tables import load  # noqa: E402
from ideas_hpc.flyby.flight import fly  # noqa: E402
from ideas_hpc.campaign.setup import setup_from_campaign  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = ROOT / "campaigns" / "eros-nadir-ga.toml"


def main() -> None:
    tmp = Path(tempfile.mkdtemp(prefix="bench_ga_"))
    try:
        times = {}
        for mode in ("ideal", "simulated"):
            out = tmp / f"{mode}.zarr"
            t = time.perf_counter()
            run_file(CAMPAIGN, out=out, overrides=[f'attitude.mode="{mode}"'], workers=2,
                     progress=False)
            times[mode] = time.perf_counter() - t
            ds = xr.open_zarr(out)
            ev = int(ds.attrs["ga_evaluations"])
            print(f"{mode:9s}: {times[mode]:.1f} s wall ({ds.attrs['ga_wall_s']:.1f} s in the GA "
                  f"incl. masks), {ev} designs, {ev / times[mode]:.0f} designs/s; best N = "
                  f"{int(ds['best_swarm_size'])}, coverage {100 * float(ds['best_coverage']):.3f} %")
        c = load(CAMPAIGN, ['attitude.mode="ideal"'])
        setup = setup_from_campaign(c)
        rng = np.random.default_rng(0)
        fly(setup, [0.1, 2.0, 4.0])  # compile
        t = time.perf_counter()
        n_eval = 10
        for _ in range(n_eval):
            n = int(rng.integers(1, 21))
            fly(setup, rng.uniform(0, 2 * np.pi, n), counts=False)
        per = (time.perf_counter() - t) / n_eval
        print(f"naive per-individual flyby evaluation: {per * 1e3:.0f} ms each -> "
              f"{per * ev / 60:.1f} min for {ev} designs on one core")
        print(f"ga: {times['simulated']:.1f} s for the paper-sized NP GA (simulated attitude)")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
