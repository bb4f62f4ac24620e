"""SPICE out (issue 32, deliverable 2): ``ideas-hpc export STORE`` read back with spiceypy.

The positions SPICE gives for each spacecraft relative to the body, in the body frame
the export's own PCK and frame kernel define, must equal the store's ``position`` (frame
T) within 1 mm; the camera attitudes the CK gives relative to that frame must equal the
store's ``camera_dcm_BT`` snapshots within 1 microradian. So the J2000 states and
quaternions the export computed, and SPICE's rotation back through the exported frames,
close the loop on the store itself.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

sp = pytest.importorskip("spiceypy")

from ideas_hpc.export.kernels import export_store  # noqa: E402
from ideas_hpc.campaign.run import run_file  # noqa: E402
from ideas_hpc.base.errors import InputError  # noqa: E402
from campaign_copies import fitted  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SETS = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3",
        'attitude.mode="ideal"', "flyby.epoch_s=5000.0"]
BID = 2000433


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    root = tmp_path_factory.mktemp("export")
    # the shipped flyby without what an ideal attitude does not read ([controller], its start)
    store = run_file(fitted("eros-flyby.toml", SETS), out=root / "fb.zarr",
                     overrides=SETS, workers=0, progress=False)
    out = export_store(store, root / "kernels", body_id=BID, epoch_et=8.0e8)
    sp.furnsh(str(out / "export.tm"))
    yield store, out
    sp.unload(str(out / "export.tm"))


def test_spk_reads_back_the_store_positions_within_1_mm(exported):
    store, out = exported
    ds = xr.open_zarr(store)
    pos, times = ds["position"].values, ds["time"].values
    worst = 0.0
    for k in range(pos.shape[0]):
        for i in range(0, times.size, 7):
            et = 8.0e8 + 5000.0 + float(times[i])
            r, _ = sp.spkpos(str(-1000 - k), et, f"IDEAS_{BID}_FIXED", "NONE", str(BID))
            worst = max(worst, float(np.linalg.norm(np.asarray(r) * 1e3 - pos[k, i])))
    print(f"SPK read back: worst {worst:.3g} m")
    assert worst < 1e-3, worst


def test_ck_reads_back_the_camera_attitudes_within_1_microradian(exported):
    store, out = exported
    ds = xr.open_zarr(store)
    dcm, t_snap = ds["camera_dcm_BT"].values, ds["snapshot_time"].values
    worst = 0.0
    for k in range(dcm.shape[0]):
        for j, t in enumerate(t_snap):
            et = 8.0e8 + 5000.0 + float(t)
            ticks = sp.sce2c(-1000 - k, et)
            cmat, _ = sp.ckgp((-1000 - k) * 1000, ticks, 0.0, f"IDEAS_{BID}_FIXED")  # raises if none
            rel = np.asarray(cmat) @ dcm[k, j].T
            worst = max(worst, math.acos(min(1.0, 0.5 * (np.trace(rel) - 1.0))))
    print(f"CK read back: worst {worst:.3g} rad")
    assert worst < 1e-6, worst


def test_ck_rates_of_an_ideal_nadir_camera_are_the_body_spin(exported):
    """Ideal nadir pointing keeps each camera fixed in the ring frame, which is fixed in
    the body frame: its angular velocity is the body's spin, which SPICE gives from the
    exported PCK (``xf2rav`` of J2000 -> body frame: the body frame's rate in J2000)."""
    store, out = exported
    n_sc = xr.open_zarr(store).sizes["spacecraft"]
    worst = 0.0
    for k in range(n_sc):
        for t in np.linspace(0.0, 60.0, 13):
            et = 8.0e8 + 5000.0 + float(t)
            _, av, _ = sp.ckgpav((-1000 - k) * 1000, sp.sce2c(-1000 - k, et), 0.0, "J2000")
            spin = sp.xf2rav(sp.sxform("J2000", f"IDEAS_{BID}_FIXED", et))[1]
            worst = max(worst, float(np.linalg.norm(np.asarray(av) - np.asarray(spin))))
    print(f"CK rates: worst {worst:.3g} rad/s against the spin")
    assert worst < 1e-12, worst


def test_csv_has_every_image_and_matches_the_spk(exported):
    store, out = exported
    rows = list(csv.DictReader(open(out / "images.csv")))
    ds = xr.open_zarr(store)
    n_sc = ds.sizes["spacecraft"]
    n_img = int(round(60.0 * 5.0)) + 1                 # 60 s at 5 Hz, both ends
    assert len(rows) == n_sc * n_img
    for row in rows[:: 97]:
        r, _ = sp.spkpos(row["naif_id"], float(row["et_tdb_s"]), "J2000", "NONE", str(BID))
        xyz = np.array([float(row[c]) for c in ("x_m", "y_m", "z_m")])
        assert np.linalg.norm(np.asarray(r) * 1e3 - xyz) < 1e-3
        q = np.array([float(row[c]) for c in ("q0", "q1", "q2", "q3")])
        assert abs(np.linalg.norm(q) - 1.0) < 1e-12
        s = np.array([float(row[c]) for c in ("sun_x", "sun_y", "sun_z")])
        assert abs(np.linalg.norm(s) - 1.0) < 1e-12


def test_export_refuses_what_it_cannot_write(exported, tmp_path):
    store, _ = exported
    with pytest.raises(InputError) as ei:
        export_store(store, tmp_path / "k", body_id=BID, naif_base=5)
    assert ei.value.field == "--naif-base"
    with pytest.raises(InputError) as ei:
        export_store(store, tmp_path / "k")          # the ellipsoid has no NAIF ID
    assert ei.value.field == "--body-id"


def test_usable_column_is_the_body_in_view(exported):
    rows = list(csv.DictReader(open(exported[1] / "images.csv")))
    assert all(r["usable"] == "1" for r in rows)       # nadir pointing keeps the body in view
    from ideas_hpc.export.kernels import body_in_view
    r = np.array([[[100e3, 0.0, 0.0]]])
    away = np.array([[[[0, 1.0, 0], [0, 0, 1.0], [1.0, 0, 0]]]])   # boresight +x_T: away
    assert not body_in_view(r, away, 0.05, 17e3)[0, 0]
    toward = np.array([[[[0, 1.0, 0], [0, 0, -1.0], [-1.0, 0, 0]]]])   # boresight -x_T
    assert body_in_view(r, toward, 0.05, 17e3)[0, 0]
