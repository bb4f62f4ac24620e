"""The bad-input corpus (``tests/bad_inputs/cases.toml``): readable failures, no store.

Every case runs ``ideas-hpc run`` in this process (:func:`ideas_hpc.cli.main`)
and must exit with status 2, print at most 3 lines, name the file and line or
the field, print no traceback and leave nothing in the output folder.
"""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from ideas_hpc.cli import main

HERE = Path(__file__).resolve().parent
CAMPAIGNS = HERE.parent / "campaigns"
CASES = tomllib.loads((HERE / "bad_inputs" / "cases.toml").read_text())["case"]


def test_corpus_is_broad():
    tables = {"body", "instrument", "flyby", "swarm", "attitude", "dynamics", "spacecraft",
              "controller", "coverage", "design", "monte_carlo", "run"}
    touched = {s.split("=")[0].split(".")[0] for c in CASES for s in c.get("set", [])}
    assert len(CASES) >= 40 and tables <= touched
    assert len({c["id"] for c in CASES}) == len(CASES)


def _campaign(case: dict, folder: Path) -> Path:
    if "file" in case:
        return Path(case["file"])
    if "text" in case or "hex" in case:
        p = folder / "case.toml"
        if "hex" in case:
            p.write_bytes(bytes.fromhex(case["hex"]))
        else:
            p.write_text(case["text"])
        return p
    return CAMPAIGNS / case.get("base", "eros-flyby.toml")


@pytest.mark.parametrize("case", CASES, ids=[c["id"] for c in CASES])
def test_bad_input(case, tmp_path, capsys):
    src, out_dir = tmp_path / "src", tmp_path / "out"
    src.mkdir()
    out_dir.mkdir()
    campaign = _campaign(case, src)
    argv = ["run", str(campaign), "--out", str(out_dir / "store.zarr"), "--no-progress"]
    for s in case.get("set", []):
        argv += ["--set", s]
    argv += case.get("args", [])
    code = main(argv)
    cap = capsys.readouterr()
    text = cap.out + cap.err
    lines = text.strip().splitlines()
    assert code == 2, text
    assert 1 <= len(lines) <= 3, text
    assert "Traceback" not in text
    assert case["expect"].format(file=campaign) in text, text
    assert not list(out_dir.iterdir()), "a store or partial store was left behind"


def test_issue_command_through_the_real_cli(tmp_path):
    """The command from issue 11, as a user types it: one line, status 2, nothing written."""
    r = subprocess.run([sys.executable, "-m", "ideas_hpc.cli", "run",
                        str(CAMPAIGNS / "eros-flyby.toml"), "--set", "flyby.max_iterations=0"],
                       capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert r.returncode == 2
    assert r.stdout == "" and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "flyby.max_iterations" in r.stderr and not list(tmp_path.iterdir())
