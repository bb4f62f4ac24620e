"""SPICE in (issue 32, deliverable 1): DSK shapes, and a body's orbit, orientation and epoch
from kernels that the tests write themselves (no downloads).

Oracles: the PDS ``.tab`` of the same model (the DSK must give the same mesh, bit for
bit); SPICE's own two-body propagation (SPK type 5) and frame system (text PCK) for
the Sun direction in the body frame, which the project computes from the kernels'
values with its own Kepler ephemeris; the leap-second count for UTC -> TDB.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

sp = pytest.importorskip("spiceypy")

from ideas_hpc.body.dsk import write_dsk  # noqa: E402
from ideas_hpc.body.formats import load_shape_file  # noqa: E402
from ideas_hpc.body.shape import read_plate_tab  # noqa: E402
from ideas_hpc.campaign.setup import setup_from_campaign  # noqa: E402
from ideas_hpc.campaign.schema.campaign_tables import load, resolved_config  # noqa: E402
from ideas_hpc.base.constants import AU, MU_SUN  # noqa: E402
from ideas_hpc.dynamics.trajectory import sun_direction_T  # noqa: E402
from ideas_hpc.base.errors import InputError  # noqa: E402
from campaign_copies import fitted  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
EROS = 2000433
LEAPS = ["1972-JAN-1", "1972-JUL-1", "1973-JAN-1", "1974-JAN-1", "1975-JAN-1", "1976-JAN-1",
         "1977-JAN-1", "1978-JAN-1", "1979-JAN-1", "1980-JAN-1", "1981-JUL-1", "1982-JUL-1",
         "1983-JUL-1", "1985-JUL-1", "1988-JAN-1", "1990-JAN-1", "1991-JAN-1", "1992-JUL-1",
         "1993-JUL-1", "1994-JUL-1", "1996-JAN-1", "1997-JUL-1", "1999-JAN-1", "2006-JAN-1",
         "2009-JAN-1", "2012-JUL-1", "2015-JUL-1", "2017-JAN-1"]   # DELTA_AT 10 ... 37 s
UTC = "2029-04-13T21:46:00"


def _tab_km(path):
    rows = [ln.split() for ln in open(path) if ln.strip()]
    v = np.array([[float(x) for x in r[1:]] for r in rows if r[0] == "v"])
    f = np.array([[int(x) for x in r[1:]] for r in rows if r[0] == "f"])
    return v, f


@pytest.fixture(scope="module")
def eros_dsk(tmp_path_factory):
    from ideas_hpc.body.datapath import find_data_file, have_data_file

    if not have_data_file("eros001708.tab"):
        pytest.skip("eros001708.tab not on IDEAS_HPC_DATA")
    tab = find_data_file("eros001708.tab")
    path = tmp_path_factory.mktemp("dsk") / "eros001708.bds"
    write_dsk(path, *_tab_km(tab), body_id=EROS, frame="IAU_EROS")
    return tab, path


def test_dsk_gives_the_tab_mesh_bit_for_bit(eros_dsk):
    tab, path = eros_dsk
    a, b = load_shape_file(path), read_plate_tab(tab)
    for name in ("vertices_T", "faces", "face_normals_T", "face_areas", "vertex_normals_T",
                 "vertex_areas"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert (a.r_max, a.r_min, a.area, a.volume) == (b.r_max, b.r_min, b.area, b.volume)


def test_campaign_shape_key_flies_the_same_body(eros_dsk):
    tab, path = eros_dsk
    nadir = ROOT / "campaigns" / "eros-nadir.toml"
    s_dsk = setup_from_campaign(load(nadir, [f'body.shape="{path}"']))
    s_tab = setup_from_campaign(load(nadir, [f'body.shape="{tab}"']))
    assert np.array_equal(s_dsk.body.shape.vertices_T, s_tab.body.shape.vertices_T)
    assert s_dsk.body.params == s_tab.body.params and s_dsk.d_sep_m == s_tab.d_sep_m
    assert s_dsk.eta_rad == s_tab.eta_rad


def test_dsk_flyby_coverage_is_bit_for_bit(eros_dsk):
    """The same flyby over the DSK and the .tab: identical per-vertex results."""
    from ideas_hpc.flyby.flight import fly

    tab, path = eros_dsk
    short = ["flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3", 'attitude.mode="ideal"',
             "swarm.angles_rad=[0.2, 1.7]", 'coverage.mode="exact"', "coverage.occlusion=true"]
    out = []
    for shape in (path, tab):
        c = load(fitted("eros-flyby.toml", short), short + [f'body.shape="{shape}"'])
        out.append(fly(setup_from_campaign(c), c.config.swarm.angles_rad))
    a, b = out
    assert np.array_equal(a.coverage.observed, b.coverage.observed)
    assert np.array_equal(a.coverage.times_seen, b.coverage.times_seen)
    assert np.array_equal(a.coverage.first_seen, b.coverage.first_seen, equal_nan=True)
    assert a.coverage.coverage == b.coverage.coverage and 0.2 < a.coverage.coverage < 1.0


def test_true_anomaly_inverts_keplers_equation():
    """The kernel values' true anomaly (one Kepler solver, the ephemeris's): from a true
    anomaly nu, E = 2 atan(sqrt((1-e)/(1+e)) tan(nu/2)) and M = E - e sin E (the forward
    direction needs no solver); back from M it must give nu."""
    from ideas_hpc.campaign.schema.spice_table import true_anomaly

    worst = 0.0
    for e in (0.0, 0.2229, 0.7, 0.95):
        for nu in np.linspace(-3.1, 3.1, 25):
            E = 2.0 * math.atan(math.sqrt((1 - e) / (1 + e)) * math.tan(nu / 2))
            back = true_anomaly(E - e * math.sin(E), e)
            worst = max(worst, abs(math.remainder(back - nu, 2 * math.pi)))
    assert worst < 1e-12, worst


def test_kernel_values_repeat_without_the_kernels():
    """``SpiceValues.params_keys()`` written as [body.params] keys give the same parameters."""
    from ideas_hpc.body.params import get_params, params_from_mapping
    from ideas_hpc.campaign.schema.spice_table import SpiceValues, apply_spice

    v = SpiceValues("2029-04-13T21:46:00", 9.2e8, "EROS", "IAU_EROS", 1.9e11, 0.21, 0.19, 5.3,
                    3.1, 2.2, 0.198, 0.3, 1.26, 18972.9)
    eros = get_params("eros")
    direct = apply_spice(eros, v)
    table = {"mass_kg": eros.mass, "c20_km2": eros.c20 / 1e6, "c22_km2": eros.c22 / 1e6,
             **v.params_keys()}
    again = params_from_mapping(table, name=eros.name)
    for f in ("orbit_a", "orbit_e", "orbit_i", "orbit_raan", "orbit_argp", "orbit_nu", "pole_ra",
              "pole_dec", "prime_meridian", "spin_period", "mu", "c20", "c22"):
        assert getattr(again, f) == pytest.approx(getattr(direct, f), rel=1e-13, abs=1e-15), f


def _write_kernels(d: Path, state0_km, et0):
    lsk = d / "test.tls"
    leaps = "\n".join(f"    {10 + k}, @{day}" for k, day in enumerate(LEAPS))  # short lines
    lsk.write_text("\\begindata\nDELTET/DELTA_T_A = 32.184\nDELTET/K = 1.657D-3\n"
                   "DELTET/EB = 1.671D-2\nDELTET/M = ( 6.239996D0 1.99096871D-7 )\n"
                   f"DELTET/DELTA_AT = (\n{leaps} )\n\\begintext\n")
    pck = d / "eros.tpc"
    pck.write_text("\\begindata\nBODY2000433_POLE_RA = ( 11.35 0. 0. )\n"
                   "BODY2000433_POLE_DEC = ( 17.22 0. 0. )\n"
                   "BODY2000433_PM = ( 326.07 1639.38864745 0. )\n\\begintext\n")
    spk = d / "eros.bsp"
    handle = sp.spkopn(str(spk), "test", 0)
    sp.spkw05(handle, EROS, 10, "ECLIPJ2000", et0 - 86400.0, et0 + 86400.0, "eros two-body",
              MU_SUN / 1e9, 1, [state0_km], [et0])
    sp.spkcls(handle)
    return [str(lsk), str(pck), str(spk)]


def _angle(a, b) -> float:
    """Angle between two vectors, atan2(|a x b|, a . b): accurate near 0, unlike acos."""
    return math.atan2(float(np.linalg.norm(np.cross(a, b))), float(np.dot(a, b)))


def _et_oracle(utc: str) -> float:
    """TDB - UTC = 37 + 32.184 s in 2029, plus a periodic term below 1.7 ms."""
    from datetime import datetime

    t = datetime.fromisoformat(utc)
    days = (t - datetime(2000, 1, 1, 12, 0, 0)).total_seconds()
    return days + 37.0 + 32.184


def test_kernels_give_the_sun_direction_spice_gives(tmp_path):
    et_guess = _et_oracle(UTC)
    # An Eros-like heliocentric state (km, km/s) at the epoch, in the ecliptic frame.
    r = 1.3 * AU / 1e3
    v = math.sqrt(MU_SUN / 1e9 / r) * 1.08
    state0 = np.array([r * 0.6, r * 0.8, 0.05 * r, -v * 0.78, v * 0.62, 0.09 * v])
    kernels = _write_kernels(tmp_path, state0, et_guess)
    kernel_toml = "[" + ", ".join(f'"{k}"' for k in kernels) + "]"
    ideal = ["attitude.mode=\"ideal\""]
    c = load(fitted("eros-flyby.toml", ideal),
             [f"body.kernels={kernel_toml}", f'flyby.epoch_utc="{UTC}"'] + ideal)
    val = c.extras["spice"]
    assert abs(val.epoch_et_s - et_guess) < 2e-3
    setup = setup_from_campaign(c)
    times = np.array([0.0, 600.0, 3 * 3600.0])
    ours = sun_direction_T(setup.body.params, setup.epoch_s + times)
    for k in kernels:
        sp.furnsh(k)
    try:
        ref = np.array([sp.spkpos("SUN", val.epoch_et_s + t, "IAU_EROS", "NONE", "EROS")[0]
                        for t in times])
    finally:
        for k in kernels:
            sp.unload(k)
    ref /= np.linalg.norm(ref, axis=1)[:, None]
    ang = np.array([_angle(a, b) for a, b in zip(ours, ref)])
    assert np.all(ang < 1e-9), ang
    assert setup.body.params.spin_period == pytest.approx(360.0 / 1639.38864745 * 86400, rel=1e-12)
    # The store's resolved config records what the kernels gave.
    rc = resolved_config(c)
    assert rc["models"]["spice"]["epoch_et_s"] == val.epoch_et_s
    assert rc["models"]["spice"]["pole_dec_rad"] == val.pole_dec_rad


def test_no_kernels_changes_nothing_and_errors_name_the_key(tmp_path):
    c = load(ROOT / "campaigns" / "eros-flyby.toml")
    assert "spice" not in c.extras and "spice" not in resolved_config(c)["models"]
    with pytest.raises(InputError) as ei:
        load(ROOT / "campaigns" / "eros-flyby.toml", [f'flyby.epoch_utc="{UTC}"'])
    assert ei.value.field == "flyby.epoch_utc"
    with pytest.raises(InputError) as ei:
        load(ROOT / "campaigns" / "eros-flyby.toml", ['body.kernels=["/nonexistent.tls"]',
                                                      f'flyby.epoch_utc="{UTC}"'])
    assert ei.value.field == "body.kernels"


def test_missing_spiceypy_is_one_line_naming_the_key(monkeypatch, tmp_path):
    import builtins

    real = builtins.__import__

    def no_spice(name, *a, **k):
        if name == "spiceypy":
            raise ImportError("no spiceypy")
        return real(name, *a, **k)

    monkeypatch.setattr(builtins, "__import__", no_spice)
    p = tmp_path / "x.bds"
    p.write_bytes(b"DAS/DSK")
    with pytest.raises(InputError) as ei:
        load_shape_file(p)
    assert ei.value.field == "body.shape" and "ideas_hpc[spice]" in ei.value.message


def test_encounter_from_a_spacecraft_spk(tmp_path):
    """A straight pass (150 km miss, 10 km/s, SPK type 13 relative to Eros in J2000) gives
    the closest-approach epoch, miss distance and v_inf in IAU_EROS; the flyby places its
    closest approach at that epoch (Sun direction there as SPICE gives it)."""
    et_guess = _et_oracle(UTC)
    r = 1.3 * AU / 1e3
    v = math.sqrt(MU_SUN / 1e9 / r) * 1.08
    kernels = _write_kernels(tmp_path, np.array([r * 0.6, r * 0.8, 0.05 * r, -v * 0.78,
                                                 v * 0.62, 0.09 * v]), et_guess)
    t_ca = et_guess + 3.3 * 3600.0 + 0.37
    u = np.array([0.6, -0.48, 0.64]) / np.linalg.norm([0.6, -0.48, 0.64])
    b = np.cross(u, [0.0, 0.0, 1.0])
    b *= 150.0 / np.linalg.norm(b)
    times = t_ca + np.arange(-1.2 * 86400, 1.2 * 86400 + 1, 600.0)
    states = np.array([np.concatenate([b + 10.0 * u * (t - t_ca), 10.0 * u]) for t in times])
    spk = tmp_path / "sc.bsp"
    h = sp.spkopn(str(spk), "sc", 0)
    sp.spkw13(h, -999, EROS, "J2000", times[0], times[-1], "pass", 3, len(times), states, times)
    sp.spkcls(h)
    kernels.append(str(spk))
    toml = "[" + ", ".join(f'"{k}"' for k in kernels) + "]"
    camp = tmp_path / "enc.toml"
    camp.write_text(f"""kind = "flyby"
[body]
name = "eros"
kernels = {toml}
[flyby]
geometry = "encounter"
epoch_utc = "{UTC}"
spice_spacecraft = "-999"
[attitude]
mode = "ideal"
[swarm]
angles_rad = [0.0, 3.0]
""")
    c = load(camp)
    val = c.extras["spice"]
    assert abs(val.ca_et_s - t_ca) < 1e-3
    assert val.miss_m == pytest.approx(150e3, abs=1e-3)
    setup = setup_from_campaign(c)
    assert setup.encounter.speed_m_s == pytest.approx(1e4, rel=1e-9)
    assert setup.epoch_s + setup.encounter.t_ca_s == pytest.approx(t_ca - val.epoch_et_s, abs=1e-3)
    for k in kernels:
        sp.furnsh(k)
    try:
        v_T = np.asarray(sp.pxform("J2000", "IAU_EROS", t_ca)) @ (10.0 * u) * 1e3
        sun = np.asarray(sp.spkpos("SUN", t_ca, "IAU_EROS", "NONE", "EROS")[0])
    finally:
        for k in kernels:
            sp.unload(k)
    np.testing.assert_allclose(val.v_inf_T_m_s, v_T, rtol=0, atol=1e-6)
    ours = sun_direction_T(setup.body.params, [setup.epoch_s + setup.encounter.t_ca_s])[0]
    assert _angle(ours, sun) < 1e-9
