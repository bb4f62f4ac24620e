"""Shared fixtures. Tests find the Eros data through IDEAS_HPC_DATA (``.ci/run``
sets it to ../shared/data); when it is unset and ../shared/data exists beside
the checkout, that folder is used, so a plain ``pytest`` works in a checkout."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

# Under CI=true a skip is a failure (a missing data path or Chromium must not pass).
from ci_skips import pytest_runtest_makereport  # noqa: E402,F401  (the hook)

ROOT = Path(__file__).resolve().parent.parent
_SHARED = ROOT.parent / "shared" / "data"
if not os.environ.get("IDEAS_HPC_DATA") and _SHARED.is_dir():
    os.environ["IDEAS_HPC_DATA"] = str(_SHARED)
# Subprocesses, dask workers and SLURM jobs started by the tests import the toy
# campaign (tests/toy_campaign.py) by name.
_TESTS = str(Path(__file__).resolve().parent)
if _TESTS not in os.environ.get("PYTHONPATH", "").split(os.pathsep):
    os.environ["PYTHONPATH"] = os.pathsep.join(
        p for p in (_TESTS, os.environ.get("PYTHONPATH", "")) if p)


@pytest.fixture(scope="session")
def eros1708():
    """The real eros001708 body, or skip when the data path does not have it."""
    from ideas_hpc.body.bodies import load_body
    from ideas_hpc.body.datapath import have_data_file

    if not have_data_file("eros001708.tab"):
        pytest.skip("eros001708.tab not on IDEAS_HPC_DATA")
    return load_body("eros001708")
