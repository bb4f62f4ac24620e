"""Results on stdout, progress and logs on stderr (issue 33): ``ideas-hpc run ... > out``
keeps the result; counts read "1 sample", not "1 samples"."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from ideas_hpc.campaign.montecarlo import coverage_result
from ideas_hpc.cli import main
from ideas_hpc.base.progress import plural

CAMPAIGNS = Path(__file__).resolve().parent.parent / "campaigns"
SMALL = ["--set", 'body.name="ellipsoid"', "--set", "flyby.tf_s=60",
         "--set", "flyby.z_start_km=-3", "--set", "flyby.z_stop_km=3"]


def test_plural():
    assert [plural(n, "sample") for n in (0, 1, 2)] == ["0 samples", "1 sample", "2 samples"]
    assert plural(1, "vertex", "vertices") == "1 vertex"
    assert plural(3, "vertex", "vertices") == "3 vertices"


def test_monte_carlo_result_line_counts_what_it_says():
    cov = np.array([1.0, 0.9995, 0.95, np.nan])
    line = coverage_result(cov, np.array([0, 1, 2, 0]), 0.999)
    # 2 of the 3 finished samples reach 99.9 %; two lost a spacecraft; one unfinished
    assert "P(coverage >= 99.90 %) = 66.7 % over 3 samples" in line
    assert "min 95.00 %" in line and "median 99.95 %" in line and "max 100.00 %" in line
    assert "2 samples with a failed spacecraft" in line and "1 sample not finished" in line


@pytest.mark.parametrize("campaign, extra, result, log", [
    ("eros-flyby.toml", ["--set", "attitude.decimate=10"], "flyby: 8 spacecraft, coverage",
     "body: "),
    ("eros-monte-carlo.toml", ["--set", "attitude.decimate=10", "--set",
                               "monte_carlo.samples=1"],
     "Monte Carlo result: P(coverage >= 99.90 %) = ", "1 sample in"),
])
def test_run_prints_its_result_on_stdout_and_logs_on_stderr(tmp_path, capsys, campaign, extra,
                                                             result, log):
    code = main(["run", str(CAMPAIGNS / campaign), "--out", str(tmp_path / "s.zarr"),
                 "--workers", "0", "--no-progress", *SMALL, *extra])
    cap = capsys.readouterr()
    assert code == 0
    assert result in cap.out and result not in cap.err
    assert log in cap.err and log not in cap.out
    # "1 samples" as a count, not the tail of a rate such as "63.1 samples/s"
    assert not re.search(r"(?<![\d.])1 samples", cap.out + cap.err)
