import subprocess
import sys

import pytest

from ideas_hpc.cli import main


def run_cli(*args, env=None):
    return subprocess.run([sys.executable, "-m", "ideas_hpc.cli", *args], capture_output=True,
                          text=True, env=env, timeout=120)


def test_size_paper_prints_table3(capsys):
    assert main(["size", "--paper"]) == 0
    out = capsys.readouterr().out
    assert "145.4545" in out and "155.9005" in out and "3.8273" in out


def test_size_eros1708(eros1708, capsys):
    assert main(["size", "--body", "eros001708"]) == 0
    out = capsys.readouterr().out
    assert "real NASA PDS" in out and "155.8881" in out and "1708 faces" in out


def test_size_given_radius(capsys):
    assert main(["size", "--r-av", "10.446"]) == 0
    assert "155.9005" in capsys.readouterr().out


@pytest.mark.parametrize("args,needle", [
    (["size", "--body", "vesta"], "unknown body 'vesta'"),
    (["size", "--r-av", "10", "--elevation", "90"], "min_elevation"),
    (["size", "--r-av", "10", "--aperture", "0"], "aperture"),
    (["size", "--r-av", "10", "--resolution", "-1"], "ground_resolution"),
    (["size", "--body", "/nonexistent/x.tab"], "no such shape file"),
])
def test_bad_input_one_line_exit_2(args, needle):
    r = run_cli(*args)
    assert r.returncode == 2
    assert needle in r.stderr
    assert "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_bad_tab_file_names_line(tmp_path):
    p = tmp_path / "cut.tab"
    p.write_text("v 1 0 0\nv 0 1 0\nv 0 0 1\nv 0 0 0\nf 0 1\n")
    r = run_cli("size", "--body", str(p))
    assert r.returncode == 2 and f"{p}:5" in r.stderr and "Traceback" not in r.stderr
