"""Flyby-layer errors reach the user under the campaign file's key, file and line.

The flyby layer names its own parameters (``max_iter``, ``d_sep_m``,
``phase_angle_rad``, ``theta``); the campaign layer maps them
(:data:`ideas_hpc.campaign.schema.model_fields.FLYBY_FIELDS`). The ``--set`` cases of
``tests/bad_inputs/cases.toml`` check the key; these check the *line*: the
oracle is the line of the TOML entry, found by searching the file's text, for
errors raised while the setup is built and while a kind flies (flyby, Monte
Carlo, GA design).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from ideas_hpc.cli import main

CAMPAIGNS = Path(__file__).resolve().parent.parent / "campaigns"
ELLIPSOID = ('name = "eros"', 'name = "ellipsoid"')


def _campaign(tmp_path, base, edits=(), append=""):
    text = (CAMPAIGNS / base).read_text()
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new, 1)
    p = tmp_path / "case.toml"
    p.write_text(text + append)
    return p


def _line(path: Path, entry: str) -> int:
    """1-based line of ``entry`` in the file (the oracle)."""
    hits = [i for i, s in enumerate(path.read_text().splitlines(), 1) if s.startswith(entry)]
    assert len(hits) == 1, hits
    return hits[0]


def _run(tmp_path, campaign, capsys, *args) -> str:
    out = tmp_path / "out"
    out.mkdir()
    code = main(["run", str(campaign), "--out", str(out / "s.zarr"), "--no-progress", *args])
    text = capsys.readouterr().err
    assert code == 2 and "Traceback" not in text and not list(out.iterdir()), text
    return text


TARGETING = [("tolerance_m = 0.01", "tolerance_m = 1e-5"),
             ("max_iterations = 25", "max_iterations = 1")]
#: ideal attitude: without what only a closed loop reads (the file's controller, its start)
IDEAL = [('mode = "simulated"', 'mode = "ideal"'), ('[controller]\npreset = "np"', ''),
         ('attitude_start = "paper"', '')]
FLYBY_EDITS = [ELLIPSOID, *IDEAL,
               ("angles_rad = [0.2, 1.7, 2.4, 2.9, 3.3, 3.5, 5.6, 6.0]",
                "angles_rad = [0.2, 3.3]")] + TARGETING
FLYBY_APPEND = "\n[flyby]\ntolerance_m = 1e-5\nmax_iterations = 1\n"


@pytest.mark.parametrize("base,edits,append,args", [
    ("eros-flyby.toml", FLYBY_EDITS, "", []),
    ("eros-monte-carlo.toml", [ELLIPSOID], FLYBY_APPEND, ["--workers", "1"]),
    ("eros-nadir-ga.toml", [ELLIPSOID], FLYBY_APPEND, ["--workers", "1"]),
], ids=["flyby", "monte-carlo", "design-ga"])
def test_targeting_failure_names_the_line(tmp_path, capsys, base, edits, append, args):
    p = _campaign(tmp_path, base, edits, append)
    text = _run(tmp_path, p, capsys, *args)
    where = f"{p}:{_line(p, 'max_iterations = 1')}: flyby.max_iterations: targeting did not"
    assert where in text and "raise flyby.max_iterations (now 1)" in text, text


#: an encounter: its window replaces the paper pass's end time and heights
ENCOUNTER = [ELLIPSOID, ('configuration = "ring"',
                         'configuration = "ring"\ngeometry = "encounter"'),
             ("tf_s = 600.0\nz_start_km = -30.0\nz_stop_km = 30.0\n", "")]


@pytest.mark.parametrize("extra,entry,key,says", [
    ("approach_dec_deg = 89.0\nphase_angle_deg = 10.0\n", "phase_angle_deg",
     "flyby.phase_angle_deg", "10 deg cannot be reached"),
    ("d_sep_km = 5.0\n", "d_sep_km", "flyby.d_sep_km",
     "increase flyby.d_sep_km (now 5 km)"),
    ("speed_km_s = 1.0\nd_sep_km = 3.0\nbefore_km = 1.0\n", "before_km", "flyby.before_km",
     "further out (flyby.before_km or before_s) with the ring outside R_max (flyby.d_sep_km)"),
])
def test_encounter_errors_name_the_line(tmp_path, capsys, extra, entry, key, says):
    edits = ENCOUNTER + [("dt_s = 0.1\n", "dt_s = 0.1\n" + extra),
                         ("[swarm]\n", "[swarm]\nmin_separation_km = 0.1\n")]
    p = _campaign(tmp_path, "eros-flyby.toml", edits)
    text = _run(tmp_path, p, capsys)
    assert f"{p}:{_line(p, entry)}: {key}: " in text and says in text and "`" not in text, text


def test_ring_spacing_names_the_angles_line(tmp_path, capsys):
    p = _campaign(tmp_path, "eros-flyby.toml", [
        ("angles_rad = [0.2, 1.7, 2.4, 2.9, 3.3, 3.5, 5.6, 6.0]", "angles_rad = [0.2, 0.2001]")])
    text = _run(tmp_path, p, capsys)
    assert f"{p}:{_line(p, 'angles_rad')}: swarm.angles_rad: spacecraft 0 and 1" in text
    assert "the minimum is swarm.min_separation_km = 1" in text, text


def test_scan_names_the_file_key(tmp_path):
    """The arrival scan flies the setup outside ``run``: same key (no file line, as before)."""
    from ideas_hpc.campaign.scan import scan_file
    from ideas_hpc.base.errors import InputError

    p = _campaign(tmp_path, "eros-flyby.toml", FLYBY_EDITS)
    with pytest.raises(InputError) as ei:
        scan_file(p, n=1)
    assert ei.value.field == "flyby.max_iterations"
    assert "raise flyby.max_iterations (now 1)" in ei.value.message
