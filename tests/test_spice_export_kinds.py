"""SPICE out of design and Monte Carlo stores (issue 32): ``ideas-hpc export`` read back.

Each oracle is what the store holds, never the export's own arrays:

* a design store (exact, success probability, FoV sweep periods): its ``position`` of
  the chosen swarm (frame T) within 1 mm, its ``camera_dcm_BT`` snapshots within 1
  microradian;
* a Monte Carlo store's nominal flight: its ``position``;
* a Monte Carlo sample K: it starts at the nominal start plus the stored
  ``position_error[K]`` and ends ``arrival_error[K]`` from the nominal arrival (1 mm);
  its camera is the stored misalignment on the stored attitude error on the ring's
  nadir reference, and its CK rate the stored ``omega_error`` plus the reference's
  spin; its failed spacecraft (stored ``active``) have no usable image.
"""

from __future__ import annotations

import csv
import math
import shutil

import numpy as np
import pytest
import xarray as xr

sp = pytest.importorskip("spiceypy")

from small_stores import CAMPAIGNS, KINDS  # noqa: E402

from ideas_hpc.export.kernels import export_store  # noqa: E402
from ideas_hpc.campaign.run import run_file  # noqa: E402
from ideas_hpc.base.errors import InputError  # noqa: E402

BID = 2000433
ET0 = 8.0e8                 # TDB of the element epoch
EPOCH_S = 5000.0            # flyby.epoch_s of every store here
FIXED = f"IDEAS_{BID}_FIXED"
MC_SETS = ["monte_carlo.failure_probability=0.3"]   # a failed spacecraft in some sample


def _store(root, kind, extra=()):
    campaign, sets, _ = KINDS[kind]
    return run_file(CAMPAIGNS / campaign, out=root / f"{kind}.zarr",
                    overrides=sets + [f"flyby.epoch_s={EPOCH_S}", *extra], workers=0,
                    progress=False)


@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    root = tmp_path_factory.mktemp("export_kinds")
    return {"root": root,
            "design-exact": _store(root, "design-exact"),
            "design-reliability": _store(root, "design-reliability"),
            "design-fov": _store(root, "design-fov"),    # designed sweep periods
            "monte-carlo": _store(root, "monte-carlo", MC_SETS)}


def _export(store, out, **kw):
    notes: list = []
    path = export_store(store, out, body_id=BID, epoch_et=ET0, notes=notes, **kw)
    return path, notes


class _Loaded:
    def __init__(self, folder):
        self.tm = str(folder / "export.tm")

    def __enter__(self):
        sp.furnsh(self.tm)

    def __exit__(self, *exc):
        sp.unload(self.tm)


def _position_gap(store, folder) -> float:
    """Worst distance (m) between SPK positions in the exported body frame and ``position``."""
    ds = xr.open_zarr(store)
    pos, times = ds["position"].values, ds["time"].values
    worst = 0.0
    with _Loaded(folder):
        for k in range(pos.shape[0]):
            for i in range(0, times.size, 5):
                r, _ = sp.spkpos(str(-1000 - k), ET0 + EPOCH_S + float(times[i]), FIXED, "NONE",
                                 str(BID))
                worst = max(worst, float(np.linalg.norm(np.asarray(r) * 1e3 - pos[k, i])))
    return worst


def _angle(a, b) -> float:
    return math.acos(max(-1.0, min(1.0, 0.5 * (np.trace(a @ b.T) - 1.0))))


def _attitude_gap(store, folder) -> float:
    """Worst angle (rad) between the CK camera frames and the stored ``camera_dcm_BT``."""
    ds = xr.open_zarr(store)
    dcm, t_snap = ds["camera_dcm_BT"].values, ds["snapshot_time"].values
    worst = 0.0
    with _Loaded(folder):
        for k in range(dcm.shape[0]):
            for j, t in enumerate(t_snap):
                ticks = sp.sce2c(-1000 - k, ET0 + EPOCH_S + float(t))
                cmat, _ = sp.ckgp((-1000 - k) * 1000, ticks, 0.0, FIXED)
                worst = max(worst, _angle(np.asarray(cmat), dcm[k, j]))
    return worst


@pytest.mark.parametrize("kind", ["design-exact", "design-reliability", "design-fov"])
def test_design_store_reads_back_its_chosen_swarm(stores, kind, tmp_path):
    store = stores[kind]
    folder, notes = _export(store, tmp_path / "k")
    ds = xr.open_zarr(store)
    n = int(ds["best_swarm_size"].values)
    assert ds.sizes["spacecraft"] == n
    rows = list(csv.DictReader(open(folder / "images.csv")))
    assert sorted({int(r["spacecraft"]) for r in rows}) == list(range(n))
    assert f"the nominal flight of the {ds.attrs['kind']} store" in notes[0]
    gap_r, gap_a = _position_gap(store, folder), _attitude_gap(store, folder)
    print(f"{kind}: SPK {gap_r:.3g} m, CK {gap_a:.3g} rad")
    assert gap_r < 1e-3 and gap_a < 1e-6, (gap_r, gap_a)


def test_ck_rates_of_an_ideal_fov_sweep_are_the_sweep_plus_the_spin(stores, tmp_path):
    """FoV sweeping under perfect tracking turns the camera about its x axis by
    ``theta_max sin(2 pi t / P)`` on the ring frame, which turns with the body (SPEC
    section 5): ``omega = theta_max (2 pi / P) cos(2 pi t / P) x_C + spin``, from the
    store's ``theta_max_rad`` and ``sweep_period`` (central differences of the images miss
    this by ``(2 pi h / P)^2 / 6`` of the rate, 3e-4 at P = 30 s and 0.2 s images)."""
    store = stores["design-fov"]
    folder, _ = _export(store, tmp_path / "k")
    ds = xr.open_zarr(store)
    tm, periods = float(ds.attrs["theta_max_rad"]), ds["sweep_period"].values
    times = ds["time"].values
    worst = w_max = 0.0
    with _Loaded(folder):
        for i, p in enumerate(periods):
            sc = -1000 - i
            for t in times[::4]:
                et = ET0 + EPOCH_S + float(t)
                cmat, av, _ = sp.ckgpav(sc * 1000, sp.sce2c(sc, et), 0.0, "J2000")
                spin = np.asarray(sp.xf2rav(sp.sxform("J2000", FIXED, et))[1])
                rate = tm * 2 * math.pi / p * math.cos(2 * math.pi * (t - times[0]) / p)
                want = rate * np.asarray(cmat)[0] + spin
                worst = max(worst, float(np.linalg.norm(np.asarray(av) - want)))
                w_max = max(w_max, float(np.linalg.norm(want)))
    print(f"design-fov: CK rates {worst:.3g} rad/s (max rate {w_max:.3g})")
    assert worst < 1e-12, worst


def test_a_store_without_trajectories_is_flown_from_its_config(stores, tmp_path):
    import zarr

    copy = tmp_path / "nopos.zarr"
    shutil.copytree(stores["design-exact"], copy)
    shutil.rmtree(copy / "position")
    with pytest.warns(UserWarning):          # zarr 3 says consolidated metadata is an extra
        zarr.consolidate_metadata(str(copy))
    folder, notes = _export(copy, tmp_path / "k")
    assert any("holds no trajectories" in n for n in notes), notes
    gap = _attitude_gap(copy, folder)
    assert gap < 1e-6, gap
    assert _position_gap(stores["design-exact"], folder) < 1e-3


def test_monte_carlo_nominal_reads_back_the_stored_position(stores, tmp_path):
    store = stores["monte-carlo"]
    folder, notes = _export(store, tmp_path / "k")
    assert "nominal" in notes[0]
    gap = _position_gap(store, folder)
    print(f"monte-carlo nominal: SPK {gap:.3g} m")
    assert gap < 1e-3, gap


def _mrp_dcm(s):
    """[B R] of the MRP ``s`` (Schaub and Junkins eq. 3.153)."""
    x = np.array([[0, -s[2], s[1]], [s[2], 0, -s[0]], [-s[1], s[0], 0]])
    q = float(s @ s)
    return np.eye(3) + (8 * x @ x - 4 * (1 - q) * x) / (1 + q) ** 2


def _prv_dcm(v):
    """[C B] of the principal rotation vector ``v`` (Schaub and Junkins eq. 3.72)."""
    phi = float(np.linalg.norm(v))
    if phi == 0.0:
        return np.eye(3)
    e = v / phi
    x = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
    return math.cos(phi) * np.eye(3) + (1 - math.cos(phi)) * np.outer(e, e) - math.sin(phi) * x


def _ring_dcm_RT(theta):
    """Nadir reference of the paper's ring (SPEC section 5): +z toward the body centre
    from the ring point at angle theta, +x along the spin axis z_T."""
    z = -np.array([math.cos(theta), math.sin(theta), 0.0])
    x = np.array([0.0, 0.0, 1.0])
    return np.array([x, np.cross(z, x), z])


@pytest.fixture(scope="module")
def mc_sample(stores, tmp_path_factory):
    store = stores["monte-carlo"]
    ds = xr.open_zarr(store)
    failed = np.flatnonzero(~ds["active"].values.all(axis=1))
    assert failed.size, "no sample with a failed spacecraft: raise the failure probability"
    k = int(failed[0])
    folder, notes = _export(store, tmp_path_factory.mktemp("mc") / "k", sample=k)
    return store, ds, k, folder, notes


def test_monte_carlo_sample_starts_and_ends_where_the_store_says(mc_sample):
    store, ds, k, folder, notes = mc_sample
    assert f"sample {k}" in notes[0]
    nom, times = ds["position"].values, ds["time"].values
    start_err, arrival = ds["position_error"].values[k], ds["arrival_error"].values[k]
    worst_start = worst_end = 0.0
    with _Loaded(folder):
        for i in range(nom.shape[0]):
            r0, _ = sp.spkpos(str(-1000 - i), ET0 + EPOCH_S + float(times[0]), FIXED, "NONE",
                              str(BID))
            rf, _ = sp.spkpos(str(-1000 - i), ET0 + EPOCH_S + float(times[-1]), FIXED, "NONE",
                              str(BID))
            worst_start = max(worst_start, float(np.linalg.norm(
                np.asarray(r0) * 1e3 - (nom[i, 0] + start_err[i]))))
            worst_end = max(worst_end, abs(float(np.linalg.norm(np.asarray(rf) * 1e3 - nom[i, -1]))
                                           - arrival[i]))
    print(f"sample {k}: start {worst_start:.3g} m, arrival error {worst_end:.3g} m")
    assert np.max(np.linalg.norm(start_err, axis=1)) > 1.0      # a dispersed start indeed
    assert worst_start < 1e-3 and worst_end < 1e-3, (worst_start, worst_end)


def test_monte_carlo_sample_camera_and_rates_are_the_stored_attitude(mc_sample):
    store, ds, k, folder, _ = mc_sample
    theta, times = ds["swarm_angle"].values, ds["time"].values
    sig, om = ds["sigma_error"].values[k], ds["omega_error"].values[k]
    mis = ds["misalignment_prv"].values[k]
    worst_a = worst_w = 0.0
    w_max = 0.0
    with _Loaded(folder):
        for i in range(theta.size):
            sc = -1000 - i
            cb, rt = _prv_dcm(mis[i]), _ring_dcm_RT(theta[i])
            for j in range(0, times.size, 3):
                et = ET0 + EPOCH_S + float(times[j])
                ticks = sp.sce2c(sc, et)
                cmat_t, _ = sp.ckgp(sc * 1000, ticks, 0.0, FIXED)
                cmat_j, av_j, _ = sp.ckgpav(sc * 1000, ticks, 0.0, "J2000")
                br = _mrp_dcm(sig[i, j])
                worst_a = max(worst_a, _angle(np.asarray(cmat_t), cb @ br @ rt))
                # omega_BN = omega_BR + omega_RN; R is fixed in T, which spins about z_T
                # xf2rav of the J2000 -> FIXED transformation: FIXED's rate in J2000
                spin = sp.xf2rav(sp.sxform("J2000", FIXED, et))[1]
                w_b = om[i, j] + br @ rt @ (np.asarray(sp.pxform("J2000", FIXED, et)) @ spin)
                w_c = np.asarray(cmat_j) @ np.asarray(av_j)
                worst_w = max(worst_w, float(np.linalg.norm(w_c - cb @ w_b)))
                w_max = max(w_max, float(np.linalg.norm(w_b)))
    print(f"sample {k}: CK {worst_a:.3g} rad, rates {worst_w:.3g} rad/s (max rate {w_max:.3g})")
    assert worst_a < 1e-6, worst_a
    assert worst_w < 1e-9, worst_w


def test_failed_spacecraft_have_no_usable_image(mc_sample):
    _, ds, k, folder, _ = mc_sample
    active = ds["active"].values[k]
    rows = list(csv.DictReader(open(folder / "images.csv")))
    for i in np.flatnonzero(~active):
        mine = [r for r in rows if int(r["spacecraft"]) == i]
        assert mine and all(r["usable"] == "0" for r in mine)


def test_exports_refused_in_one_line(stores, tmp_path, capsys):
    from ideas_hpc.cli import main

    pareto = _store(stores["root"], "design-pareto")
    with pytest.raises(InputError) as ei:
        _export(pareto, tmp_path / "p")
    assert ei.value.field == "store" and "design-pareto" in ei.value.message
    mc = stores["monte-carlo"]
    n = xr.open_zarr(mc).sizes["sample"]
    for bad in (n, -1):
        with pytest.raises(InputError) as ei:
            _export(mc, tmp_path / "m", sample=bad)
        assert ei.value.field == "--sample" and str(bad) in ei.value.message
    with pytest.raises(InputError) as ei:
        _export(stores["design-exact"], tmp_path / "d", sample=0)
    assert ei.value.field == "--sample"
    capsys.readouterr()
    assert main(["export", str(pareto), "--body-id", str(BID), "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "design-pareto" in err[0], err
