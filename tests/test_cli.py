import subprocess
import sys
from pathlib import Path

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


def test_size_negative_radius_in_input_unit():
    r = run_cli("size", "--r-av", "-5")
    assert r.returncode == 2 and "--r-av: must be > 0 km, got -5" in r.stderr
    assert "-5000" not in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_existing_plain_file_as_out(tmp_path, capsys):
    plain = tmp_path / "notastore"
    plain.write_text("keep me")
    flyby = str(Path(__file__).parent.parent / "campaigns" / "eros-flyby.toml")
    code = main(["run", flyby, "--out", str(plain), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and "--out:" in err and "existing file, not a store" in err
    assert plain.read_text() == "keep me" and sorted(tmp_path.iterdir()) == [plain]


def test_report_on_incomplete_store_names_missing_chunks(tmp_path, capsys):
    import numpy as np
    import xarray as xr

    from ideas_hpc.engine.chunk_write import write_chunk_region
    from ideas_hpc.engine.store import create_store

    tpl = xr.Dataset({"coverage": (("sample",), np.zeros(6), {"units": "1", "long_name": "c"})})
    store = tmp_path / "mc.zarr"
    create_store(store, tpl, config={"a": 1}, campaign_seed=1, chunk_size=2)
    write_chunk_region(store, 1, 2, 4, {"coverage": np.ones(2)})
    code = main(["report", str(store)])
    err = capsys.readouterr().err
    assert code == 2 and "chunk(s) 0, 2 of 3 not done" in err and "Traceback" not in err
    assert not (tmp_path / "mc-report").exists()


def test_help_texts_plain_and_complete():
    top = run_cli("--help").stdout
    assert "``" not in top and "scan-arrival" in top and "report" in top
    run = run_cli("run", "--help").stdout
    assert "``" not in run and all(k in run for k in ("design-pareto", "monte-carlo", "flyby"))
    rep = run_cli("report", "--help").stdout
    assert "summary" in rep.split("positional arguments")[0]  # a description, not only usage
