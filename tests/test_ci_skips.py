"""CI cannot pass by skipping (tests/ci_skips.py): under CI=true a skipped test fails,
except a ``host:`` skip; outside CI it stays a skip."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent

BODY = '''
import pytest

def test_data():
    pytest.skip("eros001708.tab not on IDEAS_HPC_DATA")

def test_chromium():
    pytest.skip("chromium not installed")

@pytest.mark.skipif(True, reason="host: one CPU")
def test_host():
    pass

def test_ok():
    pass
'''


def _run(tmp_path, ci):
    (tmp_path / "test_inner.py").write_text(BODY)
    (tmp_path / "conftest.py").write_text("from ci_skips import pytest_runtest_makereport  # noqa\n")
    env = {k: v for k, v in os.environ.items() if k != "CI"}
    env["PYTHONPATH"] = os.pathsep.join([str(TESTS), env.get("PYTHONPATH", "")])
    if ci is not None:
        env["CI"] = ci
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-rA", "-p", "no:cacheprovider",
                           "-o", "addopts=", str(tmp_path / "test_inner.py")],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)


def test_ci_values():
    from ci_skips import in_ci

    assert all(in_ci({"CI": v}) for v in ("true", "True", "1", "yes"))
    assert not any(in_ci(e) for e in ({}, {"CI": ""}, {"CI": "false"}, {"CI": "0"}))


def test_skips_fail_under_ci(tmp_path):
    r = _run(tmp_path, "true")
    assert r.returncode == 1, r.stdout
    assert "2 failed, 1 passed, 1 skipped" in r.stdout, r.stdout
    assert "IDEAS_HPC_DATA" in r.stdout and "chromium" in r.stdout


def test_skips_stay_skips_outside_ci(tmp_path):
    r = _run(tmp_path, None)
    assert r.returncode == 0, r.stdout
    assert "1 passed, 3 skipped" in r.stdout, r.stdout
