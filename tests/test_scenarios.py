"""The scenario bank and the validation flights of the reliability designer (issue 20)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.design.bank import build_bank
from ideas_hpc.flyby.camera import discarded_images
from ideas_hpc.flyby.flight import Perturbation, fly_open_loop
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.montecarlo.scenarios import (build_scenario_bank, draw_world, fly_members,
                                            nominal_start)
from ideas_hpc.base.seeds import SCENARIO_STREAM, VALIDATION_STREAM

ROOT = Path(__file__).resolve().parent.parent
DESIGN = ROOT / "campaigns" / "eros-design-nominal.toml"
ELLIPSOID = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3",
             "flyby.z_stop_km=3", "dynamics.srp=false"]
QUIET = [f"monte_carlo.{k}=0.0" for k in ("sigma_c20_pct", "sigma_c22_pct", "sigma_gm_pct",
                                           "sigma_position_m", "sigma_velocity_mm_s",
                                           "sigma_misalignment_deg")]
STEP = np.deg2rad(30.0)


def _campaign(sets=()):
    c = load(DESIGN, ELLIPSOID + list(sets))
    return c, setup_from_campaign(c)


def _slice(pert: dict, c: int) -> Perturbation:
    """Candidate ``c``'s share of a whole-grid perturbation."""
    out = {}
    for k, v in pert.items():
        if k in ("ics", "ics_reference"):
            out[k] = tuple(np.ascontiguousarray(a[c:c + 1]) for a in v)
        elif k in ("params_override", "acquisition_s"):
            out[k] = v
        else:
            out[k] = np.ascontiguousarray(v[c:c + 1])
    return Perturbation(**out)


@pytest.mark.parametrize("sets", [[], ['coverage.mode="exact"', "coverage.occlusion=true",
                                       "coverage.min_elevation_deg=5.0"],
                                  ['attitude.mode="simulated"'],
                                  ['attitude.mode="simulated"',
                                   'monte_carlo.attitude_start="paper"'],
                                  ['attitude.mode="simulated"',
                                   'monte_carlo.attitude_start="acquisition"',
                                   "monte_carlo.acquisition_s=60.0"]],
                         ids=["paper", "strict", "closed-loop", "closed-loop-paper",
                              "closed-loop-acquisition"])
def test_rows_are_single_candidate_flights(sets):
    # Each row is the flyby pipeline flying that one candidate alone through the
    # scenario's draws (body-level shared, its own state error and misalignment).
    c, setup = _campaign(sets)
    mc = c.config.monte_carlo
    bank = build_scenario_bank(setup, STEP, mc, seed=7, n_scenarios=3, progress=False)
    n_c = bank.theta.size
    assert bank.rows.shape == (3, n_c, setup.body.shape.n_vertices)
    r0, v0 = nominal_start(setup, bank.theta)
    changed = discarded = kept = 0
    for s in range(3):
        pert = draw_world(mc, setup, bank.theta, 7, SCENARIO_STREAM, s)
        assert set(pert["params_override"]) == {"mu", "c20", "c22", "reflectivity"}
        start = "ics_reference" if mc.attitude_start == "reference" else "ics"
        assert (start in pert) == (setup.attitude_mode == "simulated")
        for k in range(0, n_c, 3):
            f = fly_open_loop(setup, bank.theta[k:k + 1], None, r0[k:k + 1], v0[k:k + 1],
                              _slice(pert, k))
            np.testing.assert_array_equal(bank.rows[s, k], f.coverage.observed)
            found = discarded_images(setup, f.attitude)
            if found is not None:
                discarded += int(found[0].sum() + found[1].sum())
                kept += setup.image_times.size - int(found[1].sum())
        changed += int((bank.rows[s] != bank.rows[0]).sum())
    assert changed > 0          # the scenarios differ
    if mc.attitude_start == "acquisition":
        # the rows' identity covers blinded (unsettled) and usable images alike
        assert discarded > 0 and kept > 0


def test_quiet_scenarios_are_the_nominal_bank():
    # No continuous dispersion: every scenario is the designer's nominal bank.
    c, setup = _campaign(QUIET)
    mc = c.config.monte_carlo
    nominal = build_bank(setup, STEP)
    bank = build_scenario_bank(setup, STEP, mc, seed=3, n_scenarios=2, progress=False)
    np.testing.assert_allclose(bank.theta, nominal.theta, rtol=0, atol=1e-15)
    for s in range(2):
        np.testing.assert_array_equal(bank.rows[s], nominal.masks)
    members = fly_members(setup, nominal.theta[[0, 4, 8]], None, mc, seed=3, n_samples=2,
                          progress=False)
    assert members.shape == (2, 3, setup.body.shape.n_vertices)
    for m in range(2):
        np.testing.assert_array_equal(members[m], nominal.masks[[0, 4, 8]])


def test_member_flights_use_the_validation_stream():
    c, setup = _campaign()
    mc = c.config.monte_carlo
    theta = np.deg2rad([0.0, 120.0, 240.0])
    got = fly_members(setup, theta, None, mc, seed=5, n_samples=2, progress=False)
    r0, v0 = nominal_start(setup, theta)
    for m in range(2):
        pert = draw_world(mc, setup, theta, 5, VALIDATION_STREAM, m)
        f = fly_open_loop(setup, theta, None, r0, v0, Perturbation(**pert))
        np.testing.assert_array_equal(got[m].any(axis=0), f.coverage.observed)
        for j in range(3):
            fj = fly_open_loop(setup, theta[j:j + 1], None, r0[j:j + 1], v0[j:j + 1],
                               _slice(pert, j))
            np.testing.assert_array_equal(got[m, j], fj.coverage.observed)


def test_a_later_look_flies_later_validation_samples():
    """fly_members(first=k): a validation look's own samples k, k+1, ... of the stream (issue
    29): the same flights as samples k.. of one long run, different from samples 0.."""
    c, setup = _campaign()
    mc = c.config.monte_carlo
    theta = np.deg2rad([0.0, 120.0, 240.0])
    run = fly_members(setup, theta, None, mc, seed=5, n_samples=3, progress=False)
    later = fly_members(setup, theta, None, mc, seed=5, n_samples=1, progress=False, first=2)
    np.testing.assert_array_equal(later[0], run[2])
    r0, v0 = nominal_start(setup, theta)
    pert = draw_world(mc, setup, theta, 5, VALIDATION_STREAM, 2)
    f = fly_open_loop(setup, theta, None, r0, v0, Perturbation(**pert))
    np.testing.assert_array_equal(later[0].any(axis=0), f.coverage.observed)
    first = draw_world(mc, setup, theta, 5, VALIDATION_STREAM, 0)
    assert not np.array_equal(first["position_error_T"], pert["position_error_T"])


def test_streams_share_no_seed():
    # Scenario draws, validation draws and Monte Carlo samples (and their
    # children) never share a seed sequence state.
    from ideas_hpc.base.seeds import sample_seed_sequence, stream_seed_sequence

    def words(ss):
        return tuple(ss.generate_state(4).tolist())

    for seed in (0, 2026):
        scen = {words(stream_seed_sequence(seed, SCENARIO_STREAM, k, p))
                for k in range(300) for p in range(3)}
        val = {words(stream_seed_sequence(seed, VALIDATION_STREAM, k, p))
               for k in range(300) for p in range(3)}
        mc = {words(sample_seed_sequence(seed, k, *ch)) for k in range(300)
              for ch in ((), (1,))}
        assert len(scen) == len(val) == 900 and len(mc) == 600
        assert not scen & val and not scen & mc and not val & mc
    c, setup = _campaign(QUIET)
    bank = build_scenario_bank(setup, STEP, c.config.monte_carlo, seed=3, n_scenarios=1,
                               progress=False)
    assert bank.attrs["scenario_stream"] == SCENARIO_STREAM
    assert bank.attrs["validation_stream"] == VALIDATION_STREAM


@pytest.mark.parametrize("sets", [[], ['coverage.mode="paper"', "coverage.occlusion=false",
                                       "coverage.min_elevation_deg=0.0"]],
                         ids=["strict", "paper"])
def test_fast_rows_equal_full_recomputation_on_eros(eros1708, sets):
    # The witness / budget-window / face-cone shortcuts against the flyby pipeline
    # recomputing every row of the perturbed flight, on the real (concave) Eros.
    from ideas_hpc.montecarlo.scenario_rows import full_rows
    from ideas_hpc.montecarlo.scenarios import grid_theta, row_engine

    c = load(DESIGN, sets)
    setup = setup_from_campaign(c)
    mc = c.config.monte_carlo
    theta = grid_theta(np.deg2rad(3.0))
    eng = row_engine(setup, theta, mc, 11, SCENARIO_STREAM)
    for s in (1, 2):
        pert = Perturbation(**draw_world(mc, setup, theta, 11, SCENARIO_STREAM, s))
        fast = eng.rows(*eng.flight(pert))
        full = full_rows(setup, theta, None, eng.r0_T, eng.v0_T, pert)
        np.testing.assert_array_equal(fast, full)
        assert full.any() and not full.all()
        assert (full != (eng.witness >= 0)).any()     # the scenario moved footprints


@pytest.mark.parametrize("start", ["paper", "acquisition"])
def test_closed_loop_rows_include_the_convergence(eros1708, start):
    # Closed-loop attitude from dispersed initial attitudes: the fast rows (full
    # scans while the attitude converges, budget windows after) equal the full
    # recomputation, and they differ from the ideal-attitude rows of the same world.
    # With a short acquisition the first images are unsettled and blinded: the
    # fast rows still equal the full recomputation.
    from ideas_hpc.montecarlo.scenario_rows import full_rows
    from ideas_hpc.montecarlo.scenarios import grid_theta, row_engine

    c = load(DESIGN, ['attitude.mode="simulated"', f'monte_carlo.attitude_start="{start}"']
             + (["monte_carlo.acquisition_s=60.0"] if start == "acquisition" else []))
    setup = setup_from_campaign(c)
    mc = c.config.monte_carlo
    theta = grid_theta(np.deg2rad(6.0))
    eng = row_engine(setup, theta, mc, 13, SCENARIO_STREAM)
    pert = Perturbation(**draw_world(mc, setup, theta, 13, SCENARIO_STREAM, 1))
    r_img, dcm = eng.flight(pert)
    from ideas_hpc.core.mapping.scenario_rows import deviation_start
    r_nom, dcm_nom = eng.nominal()
    i_ok, _, _ = deviation_start(r_nom, dcm_nom, r_img, dcm, *eng.budget)
    if start == "paper":
        assert np.all(i_ok > 0)                 # converging: outside the budget at first
    else:
        assert np.any(i_ok > 0)                 # blinded images: outside the budget
    fast = eng.rows(r_img, dcm)
    np.testing.assert_array_equal(fast, full_rows(setup, theta, None, eng.r0_T, eng.v0_T, pert))
    ideal = full_rows(setup.with_(attitude_mode="ideal"), theta, None, eng.r0_T, eng.v0_T, pert)
    if start == "paper":
        assert (fast != ideal).any()


def test_a_flight_the_proofs_cannot_take_is_recomputed_in_full(eros1708, monkeypatch):
    # The proofs assume near-rotation DCMs and finite positions, checked per candidate
    # inside perturbed_rows: one scaled DCM of one candidate at one image sends the
    # whole scenario to the full recomputation, one non-finite position to the full
    # path's validation, which names it.
    from ideas_hpc.base.errors import InputError
    from ideas_hpc.montecarlo.scenario_rows import RowEngine
    from ideas_hpc.montecarlo.scenarios import grid_theta, row_engine

    c = load(DESIGN, [])
    setup = setup_from_campaign(c)
    mc = c.config.monte_carlo
    theta = grid_theta(np.deg2rad(6.0))
    eng = row_engine(setup, theta, mc, 11, SCENARIO_STREAM)
    pert = Perturbation(**draw_world(mc, setup, theta, 11, SCENARIO_STREAM, 1))
    r_img, dcm = (np.array(a) for a in eng.flight(pert))
    full_calls = []
    real_full = RowEngine._full
    monkeypatch.setattr(RowEngine, "_full",
                        lambda self, *a: full_calls.append(1) or real_full(self, *a))
    eng.rows(r_img, dcm)
    assert not full_calls                               # a plain scenario: the proofs
    # |C C^T - I| = 2e-8: beyond the proofs' 1e-10, within the pipeline's 1e-6
    dcm[5, 10] *= 1.0 + 1e-8
    np.testing.assert_array_equal(eng.rows(r_img, dcm), real_full(eng, r_img, dcm))
    assert full_calls == [1]
    r_img[3, 7, 0] = np.nan
    dcm[5, 10] /= 1.0 + 1e-8
    with pytest.raises(InputError, match="r_T"):
        eng.rows(r_img, dcm)
    assert full_calls == [1, 1]
