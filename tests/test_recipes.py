"""The CONTRIBUTING recipes are true (issue 21): each registers a toy entry from
this module alone, by patching the registry the recipe names and nothing else,
and runs it end to end on the built-in ellipsoid through ``run_file``.

Each toy is checked against an independent path: a built-in campaign that must
give the same numbers, or a NumPy recomputation from the stored arrays.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from ideas_hpc.attitude import maneuvers
from ideas_hpc.campaign.schema import kinds
from ideas_hpc.campaign.run import run_file
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.core.attitude.maneuvers import FOV_MODE
from ideas_hpc.design.pareto import objectives
from ideas_hpc.base.errors import InputError
from ideas_hpc.montecarlo import dispersions
from ideas_hpc.base.fields import Field
from ideas_hpc.engine.variables import StoreVar

from campaign_copies import fitted

CAMPAIGNS = Path(__file__).resolve().parent.parent / "campaigns"
FLYBY = CAMPAIGNS / "eros-flyby.toml"
SHORT = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3",
         'attitude.mode="ideal"', "swarm.angles_rad=[0.2, 2.4, 4.1]"]
PERIODS = "swarm.sweep_periods_min=[0.5, 0.7, 0.9]"
#: the shipped flyby without what an ideal attitude does not read ([controller], its start)
IDEAL_FLYBY = fitted("eros-flyby.toml", SHORT)


def _flyby(tmp_path, name, sets, path=IDEAL_FLYBY):
    store = run_file(path, out=tmp_path / f"{name}.zarr", overrides=SHORT + sets, workers=0,
                     progress=False)
    return xr.open_zarr(store)


# --- A new attitude maneuver: one Maneuver entry (it reuses the FoV kernels' mode code)

def test_recipe_maneuver(tmp_path, monkeypatch):
    toy = maneuvers.Maneuver("toy", FOV_MODE, "fov", maneuvers._sweep_params,
                             "toy: the FoV sweep under another name", key="toy-sweep",
                             sweeps=True, fov_factor=0.5)
    monkeypatch.setitem(maneuvers.MANEUVERS, "toy", toy)
    with pytest.raises(InputError) as err:   # it declares sweep periods: the schema asks
        load(IDEAL_FLYBY, SHORT + ['attitude.maneuver="toy-sweep"'])
    assert err.value.field == "swarm.sweep_periods_min"
    a = _flyby(tmp_path, "toy", ['attitude.maneuver="toy-sweep"', PERIODS])
    fov = _flyby(tmp_path, "fov", ['attitude.maneuver="fov"', PERIODS])
    nadir = _flyby(tmp_path, "nadir", ['attitude.maneuver="nadir"'])
    assert a.attrs["maneuver"] == "toy-sweep"
    assert a.attrs["half_angle_rad"] == pytest.approx(0.5 * a.attrs["eta_nadir_rad"], rel=1e-15)
    # the same motion as the built-in FoV sweep, not silently nadir pointing
    assert np.array_equal(a["camera_dcm_BT"].values, fov["camera_dcm_BT"].values)
    assert np.array_equal(a["observed"].values, fov["observed"].values)
    assert not np.allclose(a["camera_dcm_BT"].values, nadir["camera_dcm_BT"].values)


@pytest.mark.parametrize("kernel", ["reference_into", "camera_dcm_into"])
def test_maneuver_dispatch_raises_on_a_code_it_has_no_branch_for(kernel):
    """A mode code without its kernel branch (the recipe's next code, or the tabulated
    TRACK_MODE) raises instead of flying nadir pointing."""
    from ideas_hpc.core.attitude import maneuvers as core
    from ideas_hpc.core.attitude.mrp import mrp_from_dcm

    dcm = np.ascontiguousarray(np.eye(3))
    fn = getattr(core, kernel)
    args = {"reference_into": lambda m: (m, 1.0, 1e-4, mrp_from_dcm(dcm), dcm, 0.03, 60.0,
                                         np.empty(9)),
            "camera_dcm_into": lambda m: (m, 1.0, dcm, 0.03, 60.0, np.empty((3, 3)))}[kernel]
    fn(*args(core.NP_MODE))
    fn(*args(core.FOV_MODE))
    codes = {m.code for m in maneuvers.MANEUVERS.values()}
    for bad in (max(codes) + 1, core.TRACK_MODE):
        with pytest.raises(ValueError, match="mode code"):
            fn(*args(bad))


# --- A new Monte Carlo dispersion: one Dispersion entry appended to DISPERSIONS

def _toy_gm(rng, n, mc, setup, theta):
    u = rng.uniform(-1.0, 1.0)
    return {"toy_mu": setup.body.params.mu * (1.0 + mc.toy_gm_pct / 100.0 * u), "toy_u": u}


def _toy_check(mc):
    if mc.toy_gm_pct > 50.0:
        raise InputError("must be <= 50 %", field="toy_gm_pct")


TOY_DISPERSION = dispersions.Dispersion(
    "toy_gm", _toy_gm, lambda v: {"params_override": {"mu": v["toy_mu"]}},
    (StoreVar("toy_mu", (), np.float64, "m^3/s^2", "GM (toy dispersion)"),
     StoreVar("toy_u", (), np.float64, "1", "toy uniform draw")),
    keys=(("toy_gm_pct", Field("float", 0.0, lo=0, doc="toy GM error, %")),),
    check=_toy_check, level="body", active=lambda mc, setup: mc.toy_gm_pct != 0)
MC = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3",
      'attitude.mode="ideal"', "monte_carlo.samples=3", "run.chunk_size=3",
      "monte_carlo.sigma_gm_pct=0.0"]
#: the shipped Monte Carlo without what an ideal attitude does not read (its start)
IDEAL_MC = fitted("eros-monte-carlo.toml", MC)


def _mc(tmp_path, name, sets):
    from distributed import Client, LocalCluster

    # threads in this process: the workers see the patched registry
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=":0") as cluster, Client(cluster):
        store = run_file(IDEAL_MC, out=tmp_path / f"{name}.zarr",
                         overrides=MC + sets, scheduler=cluster.scheduler_address,
                         progress=False)
    return xr.open_zarr(store)


def test_recipe_dispersion(tmp_path, monkeypatch):
    base = _mc(tmp_path, "base", [])
    with pytest.raises(InputError) as err:     # the key exists only with its entry
        load(IDEAL_MC, MC + ["monte_carlo.toy_gm_pct=5.0"])
    assert err.value.field == "monte_carlo.toy_gm_pct"
    monkeypatch.setattr(dispersions, "DISPERSIONS", dispersions.DISPERSIONS + (TOY_DISPERSION,))
    with pytest.raises(InputError) as err:     # its cross-check, named in the file's terms
        load(IDEAL_MC, MC + ["monte_carlo.toy_gm_pct=80.0"])
    assert err.value.field == "monte_carlo.toy_gm_pct"
    toy = _mc(tmp_path, "toy", ["monte_carlo.toy_gm_pct=20.0"])
    assert list(toy.attrs["dispersion_order"]) == list(base.attrs["dispersion_order"]) + ["toy_gm"]
    # appended last: every earlier draw is unchanged
    for v in ("c20", "reflectivity", "position_error", "velocity_error", "active",
              "misalignment_prv"):
        assert np.array_equal(toy[v].values, base[v].values), v
    # stored values follow from its draws; the flight saw the dispersed GM
    mu0 = base["mu"].values
    assert np.allclose(toy["toy_mu"].values, mu0 * (1 + 0.2 * toy["toy_u"].values), rtol=1e-15)
    assert toy["toy_mu"].attrs["units"] == "m^3/s^2"
    assert not np.allclose(toy["arrival_error"].values, base["arrival_error"].values)


def test_a_dispersion_must_declare_its_level_and_when_it_is_active():
    for missing in ({"level": None}, {"active": None}, {"level": "swarm"}):
        with pytest.raises(ValueError, match="level|active"):
            dataclasses.replace(TOY_DISPERSION, **missing)


RELIABILITY = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3",
               "flyby.z_stop_km=3", "dynamics.srp=false", "design.angle_step_deg=30",
               'attitude.mode="ideal"', "run.workers=0", "design.time_limit_s=30",
               "design.success_probability=0.1", "monte_carlo.failure_probability=0.05",
               "design.scenarios=12", "design.verify_samples=12", "design.n_max=6"] + [
    f"monte_carlo.{k}=0.0" for k in ("sigma_c20_pct", "sigma_c22_pct", "sigma_gm_pct",
                                     "sigma_position_m", "sigma_velocity_mm_s",
                                     "sigma_misalignment_deg")] + [
    "monte_carlo.reflectivity_min=0.6", "monte_carlo.reflectivity_max=0.6"]


def test_recipe_dispersion_reaches_the_success_probability_designer(tmp_path, monkeypatch):
    """The toy entry alone makes the designer's campaign dispersed: it is drawn into
    every scenario from the body-level generator of the seed scheme (its declared
    level), and with its key at 0 (inactive) the design is the one exact scenario."""
    from ideas_hpc.base.seeds import SCENARIO_STREAM, STREAM_BODY, stream_rng

    drawn = []

    def recorded(rng, n, mc, setup, theta):
        v = _toy_gm(rng, n, mc, setup, theta)
        drawn.append(v["toy_u"])
        return v

    monkeypatch.setattr(dispersions, "DISPERSIONS", dispersions.DISPERSIONS + (
        dataclasses.replace(TOY_DISPERSION, draw=recorded),))
    design = CAMPAIGNS / "eros-design.toml"
    off = xr.open_zarr(run_file(design, out=tmp_path / "off.zarr", overrides=RELIABILITY,
                                progress=False))
    assert off["validation_probability"].shape == (1,)          # nominal: exact
    drawn.clear()
    on = xr.open_zarr(run_file(design, out=tmp_path / "on.zarr", progress=False,
                               overrides=RELIABILITY + ["monte_carlo.toy_gm_pct=20.0"]))
    assert on["validation_probability"].shape == (12,)           # dispersed: sampled
    seed = load(design, RELIABILITY).config.seed
    for k in range(12):
        body = stream_rng(seed, SCENARIO_STREAM, k, STREAM_BODY)
        body.standard_normal(3)          # gravity, reflectivity, navigation: the entries
        body.uniform(0.0, 1.0)           # before it
        body.standard_normal(3)
        assert body.uniform(-1.0, 1.0) in drawn, k


# --- A new dispersion of the world: the target's pole, one entry and nothing else (issue 40)

def _toy_pole(rng, n, mc, setup, theta):
    ra, dec = setup.world.pole_rad       # the body's pole, or its orbit normal
    z = rng.standard_normal(2)
    s = mc.toy_sigma_pole_rad
    return {"toy_pole_ra": ra + s * z[0],
            "toy_pole_dec": float(np.clip(dec + s * z[1], -0.5 * math.pi, 0.5 * math.pi))}


TOY_POLE = dispersions.Dispersion(
    "toy_pole", _toy_pole,
    lambda v: {"params_override": {"pole_ra": v["toy_pole_ra"], "pole_dec": v["toy_pole_dec"]}},
    (StoreVar("toy_pole_ra", (), np.float64, "rad", "pole right ascension (toy dispersion)"),
     StoreVar("toy_pole_dec", (), np.float64, "rad", "pole declination (toy dispersion)")),
    keys=(("toy_sigma_pole_deg", Field("float", 0.0, si="toy_sigma_pole_rad", to_si=math.pi / 180,
                                       lo=0, doc="1-sigma pole error per angle, deg")),),
    level="body", active=lambda mc, setup: mc.toy_sigma_pole_rad != 0)
LIT = ["coverage.illumination=true"]


def test_recipe_world_dispersion_the_pole(tmp_path, monkeypatch):
    """A body-level channel that perturbs the world (the pole), registered here alone:
    the Monte Carlo kind stores its draws and flies them (lit coverage follows the
    pole), and the scenario bank draws it per scenario from the body stream and flies
    each scenario through its own world (its Sun), as the full recomputation does."""
    from ideas_hpc.base.seeds import SCENARIO_STREAM, STREAM_BODY, stream_rng
    from ideas_hpc.campaign.setup import setup_from_campaign
    from ideas_hpc.flyby.flight import Perturbation, fly_open_loop
    from ideas_hpc.montecarlo.dispersions import draw_sample
    from ideas_hpc.montecarlo.sample import design_nominal
    from ideas_hpc.montecarlo.scenario_rows import full_rows
    from ideas_hpc.montecarlo.scenarios import (build_scenario_bank, draw_world, grid_theta,
                                                nominal_start)

    base = _mc(tmp_path, "base", LIT)
    monkeypatch.setattr(dispersions, "DISPERSIONS", dispersions.DISPERSIONS + (TOY_POLE,))
    sets = LIT + ["monte_carlo.toy_sigma_pole_deg=40.0"]
    toy = _mc(tmp_path, "toy", sets)
    assert list(toy.attrs["dispersion_order"]) == list(base.attrs["dispersion_order"]) + [
        "toy_pole"]
    assert toy["toy_pole_dec"].attrs["units"] == "rad"
    for v in ("c20", "reflectivity", "position_error", "misalignment_prv"):
        assert np.array_equal(toy[v].values, base[v].values), v
    # the flight saw the stored pole: sample 0 re-flown with it (and nothing else of the
    # toy) gives the stored coverage, and the pole moved the lit coverage somewhere
    c = load(IDEAL_MC, MC + sets)
    setup = setup_from_campaign(c)
    theta = np.asarray(c.config.swarm.angles_rad)
    _, pert = draw_sample(c.config.monte_carlo, c.config.seed, 0, theta, setup)
    pole = {"pole_ra": float(toy["toy_pole_ra"].values[0]),
            "pole_dec": float(toy["toy_pole_dec"].values[0])}
    assert {k: pert["params_override"][k] for k in pole} == pole
    nom = design_nominal(setup, theta, None)
    f = fly_open_loop(setup, theta, None, nom.r0_T, nom.v0_T, Perturbation(**pert))
    assert f.coverage.coverage == float(toy["coverage"].values[0])
    assert not np.array_equal(toy["coverage"].values, base["coverage"].values)
    # the bank: one draw per scenario from the body generator, after gravity and SRP
    c = load(CAMPAIGNS / "eros-design.toml", RELIABILITY + sets)
    setup, mc = setup_from_campaign(c), c.config.monte_carlo
    bank = build_scenario_bank(setup, np.deg2rad(30.0), mc, seed=5, n_scenarios=3,
                               progress=False)
    theta = grid_theta(np.deg2rad(30.0))
    r0, v0 = nominal_start(setup, theta)
    differs = 0
    for k in range(3):
        body = stream_rng(5, SCENARIO_STREAM, k, STREAM_BODY)
        body.standard_normal(3)          # gravity, reflectivity, navigation: the entries
        body.uniform(0.0, 1.0)           # before it
        body.standard_normal(3)
        z = body.standard_normal(2)
        pert = Perturbation(**draw_world(mc, setup, theta, 5, SCENARIO_STREAM, k))
        ra, dec = setup.world.pole_rad
        assert pert.params_override["pole_ra"] == ra + mc.toy_sigma_pole_rad * z[0]
        np.testing.assert_array_equal(bank.rows[k], full_rows(setup, theta, None, r0, v0, pert))
        still = dataclasses.replace(pert, params_override=None)
        differs += not np.array_equal(bank.rows[k], full_rows(setup, theta, None, r0, v0, still))
    assert differs > 0


# --- A new disturbance torque: one settings class in TORQUE_TERMS

@dataclasses.dataclass(frozen=True)
class ToyJet:
    """Toy outgassing jet: a torque about x_B of ``torque_N_m`` times (spacecraft index + 1)."""

    torque_N_m: float = 0.0

    def _pack(self, table, ctx):
        table[:, :, 0] += self.torque_N_m * (1.0 + np.arange(ctx.theta_rad.size))[:, None]


def test_recipe_torque(monkeypatch):
    """The toy term, registered here alone, flies in a campaign's simulated flyby: once the
    controller has settled, the wheels absorb it, so their momentum ``J_s Omega`` grows by
    the torque's impulse (angular momentum balance of SPEC section 5's dynamics; the
    undisturbed flight's drift, from the gyroscopic term, subtracted)."""
    from ideas_hpc.attitude import torque_terms
    from ideas_hpc.campaign.setup import setup_from_campaign
    from ideas_hpc.flyby.flight import fly

    monkeypatch.setitem(torque_terms.TORQUE_TERMS, "toy_jet", ToyJet)
    jet = torque_terms.torques_from_config({"toy_jet": {"torque_N_m": 1e-4}})
    with pytest.raises(InputError) as err:
        torque_terms.torques_from_config({"toy_jet": {"torque_Nm": 1e-4}})
    assert err.value.field == "torques.toy_jet.torque_Nm"
    sets = [s for s in SHORT if not s.startswith("attitude.mode")] + [
        'attitude.mode="simulated"', "attitude.decimate=1"]
    setup = setup_from_campaign(load(FLYBY, sets))
    theta = np.array([0.2, 2.4, 4.1])
    quiet, loud = fly(setup, theta).attitude, fly(setup.with_(torques=jet), theta).attitude
    t = quiet.times
    late = t >= t[-1] - 20.0                 # settled (K_P = 0.4 1/s)
    j_s = setup.spacecraft.J_s
    for i in range(3):
        h = [j_s * r.wheel_speed[0, i][late] for r in (quiet, loud)]
        dh = (h[1][-1] - h[1][0]) - (h[0][-1] - h[0][0])
        impulse = 1e-4 * (i + 1) * (t[late][-1] - t[late][0])
        # about x_B, the jet's axis (the other axes see the gyroscopic coupling
        # omega x h_s of the growing wheel momentum, ~5 % here)
        assert dh[0] == pytest.approx(impulse, rel=0.03), i


def test_recipe_torque_from_the_campaign_file(tmp_path, monkeypatch):
    """The ``[torques]`` table of a campaign file chooses the registered terms: the toy jet
    written there flies as the one built in code (same wheel history), and a wrong key is
    one line naming the field and the file's line."""
    from ideas_hpc.attitude import torque_terms
    from ideas_hpc.campaign.setup import setup_from_campaign
    from ideas_hpc.flyby.flight import fly

    monkeypatch.setitem(torque_terms.TORQUE_TERMS, "toy_jet", ToyJet)
    sets = [s for s in SHORT if not s.startswith("attitude.mode")] + [
        'attitude.mode="simulated"', "attitude.decimate=1"]
    path = tmp_path / "jet.toml"
    path.write_text(FLYBY.read_text() + "\n[torques.toy_jet]\ntorque_N_m = 1e-4\n")
    from_file = setup_from_campaign(load(path, sets))
    assert from_file.torques == (ToyJet(1e-4),)
    plain = setup_from_campaign(load(FLYBY, sets))
    assert plain.torques == ()
    theta = np.array([0.2, 2.4, 4.1])
    got = fly(from_file, theta).attitude.wheel_speed
    want = fly(plain.with_(torques=(ToyJet(1e-4),)), theta).attitude.wheel_speed
    np.testing.assert_array_equal(got, want)
    assert not np.array_equal(got, fly(plain, theta).attitude.wheel_speed)
    bad = tmp_path / "bad.toml"
    bad.write_text(FLYBY.read_text() + "\n[torques.toy_jet]\ntorque_Nm = 1e-4\n")
    with pytest.raises(InputError) as err:
        load(bad, sets)
    assert err.value.field == "torques.toy_jet.torque_Nm"
    assert "bad.toml" in str(err.value)


# --- A new design objective: one Objective entry in OBJECTIVES

def _angle_sum(bank, members):
    th = np.where(members >= 0, bank.theta[np.maximum(members, 0)], 0.0)
    return th.sum(axis=1)


def test_recipe_objective(tmp_path, monkeypatch):
    monkeypatch.setitem(objectives.OBJECTIVES, "angle_sum", objectives.Objective(
        "angle_sum", -1, "rad", "sum of the swarm angles (toy)", _angle_sum))
    sets = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3",
            "design.population=8", "design.generations=3", "design.angle_step_deg=10.0",
            'design.objectives=["n", "angle_sum"]']
    # without the shipped file's time_limit_s: it bounds the exact (n, coverage) curve only
    store = run_file(fitted("eros-pareto.toml", sets), out=tmp_path / "p.zarr", workers=0,
                     progress=False, overrides=sets)
    ds = xr.open_zarr(store)
    got = ds["pareto_angle_sum"].values
    assert ds["pareto_angle_sum"].attrs["units"] == "rad" and got.size >= 1
    assert np.allclose(got, np.nansum(ds["pareto_swarm"].values, axis=1), rtol=1e-12)
    n = ds["pareto_n"].values        # non-dominated: more spacecraft, larger sum
    for i in range(n.size):
        assert not np.any((n <= n[i]) & (got >= got[i]) & ((n < n[i]) | (got > got[i])))


# --- A new campaign kind: a run function (here, in this module) and one Kind entry

def run_toy(c, out, **_):
    """Toy kind: a flyby of the first spacecraft of ``swarm.angles_rad`` only."""
    from ideas_hpc.campaign import datasets
    from ideas_hpc.flyby.flight import fly
    from ideas_hpc.campaign.setup import setup_from_campaign

    setup = setup_from_campaign(c)
    res = fly(setup, c.config.swarm.angles_rad[:1])
    ds = datasets.flyby_dataset(setup, res)
    ds.attrs.update(datasets.base_attrs(c, setup))
    return ds


def test_recipe_kind(tmp_path, monkeypatch):
    monkeypatch.setitem(kinds.KINDS, "toy-first", kinds.Kind(
        "toy-first", __name__, "run_toy", False, "a flyby of the first spacecraft"))
    toy = _flyby(tmp_path, "toy", ['kind="toy-first"'])
    one = _flyby(tmp_path, "one", ["swarm.angles_rad=[0.2]"])
    assert toy.attrs["kind"] == "toy-first" and toy.sizes["spacecraft"] == 1
    assert np.array_equal(toy["observed"].values, one["observed"].values)
    assert math.isclose(float(toy["coverage"]), float(one["coverage"]), rel_tol=0, abs_tol=0)


# --- One angle step for every designer (issue 21 item 2)

def test_one_angle_step_key_keeps_each_default_and_the_alias_warns_once(monkeypatch):
    from ideas_hpc.campaign.schema import design_checks as design_table

    monkeypatch.setattr(design_table, "_warned", [])
    exact = load(CAMPAIGNS / "eros-design.toml", ['body.name="ellipsoid"']).config.design
    ga = load(CAMPAIGNS / "eros-nadir-ga.toml", ['body.name="ellipsoid"']).config.design
    assert exact.grid_step_rad == 0.5 * math.pi / 180 and ga.angle_step_rad == 0.01
    set_ = load(CAMPAIGNS / "eros-nadir-ga.toml", ["design.angle_step_deg=2.0"]).config.design
    assert set_.angle_step_rad == pytest.approx(math.radians(2.0), rel=1e-15)
    assert set_.grid_step_rad == set_.angle_step_rad
    with pytest.warns(FutureWarning, match="angle_step_deg"):
        old = load(CAMPAIGNS / "eros-nadir-ga.toml", ["design.angle_step_rad=0.2"]).config.design
    assert old.angle_step_rad == 0.2
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")       # once: the second use is silent
        load(CAMPAIGNS / "eros-nadir-ga.toml", ["design.angle_step_rad=0.2"])


def test_designers_name_their_own_parameters():
    from ideas_hpc.base.errors import config_fields
    from ideas_hpc.design.ga.genetic import run_fov_ga
    from ideas_hpc.campaign.design_ga import GA_FIELDS

    kw = dict(n_spacecraft=2, p_min=60.0, p_max=30.0, period_step=0.0, population=4,
              generations=1, seed=1)
    with pytest.raises(InputError) as err:
        run_fov_ga(lambda g: np.zeros(len(g)), **kw)
    assert err.value.field == "p_min"
    with pytest.raises(InputError) as err, config_fields(GA_FIELDS):
        run_fov_ga(lambda g: np.zeros(len(g)), **kw)
    assert err.value.field == "design.p_min_min"
