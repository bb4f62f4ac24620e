"""pytest plugin (loaded by conftest.py): under ``CI=true`` a skipped test fails.

A CI run must not pass by skipping: a missing data path (``IDEAS_HPC_DATA``), a
missing Chromium, a missing optional test dependency or an unreachable SLURM
controller would otherwise turn real checks into skips that nobody reads. Outside
CI (a developer's checkout) skips stay skips. Only a skip whose reason starts with
``host:`` (the machine cannot run the test at all, e.g. one CPU core) is kept in CI.
"""

from __future__ import annotations

import os

import pytest

HOST_PREFIX = "host:"


def in_ci(env=os.environ) -> bool:
    return env.get("CI", "").strip().lower() in ("1", "true", "yes")


def skip_reason(rep) -> str:
    if isinstance(rep.longrepr, tuple):
        return str(rep.longrepr[2]).removeprefix("Skipped: ")
    return str(rep.longrepr)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    rep = outcome.get_result()
    if not (rep.skipped and in_ci()) or hasattr(rep, "wasxfail"):
        return
    reason = skip_reason(rep)
    if reason.startswith(HOST_PREFIX):
        return
    rep.outcome = "failed"
    rep.longrepr = (f"skipped under CI=true, which counts as a failure (tests/ci_skips.py): "
                    f"{reason}")
