"""The one-pass closed-loop variants fly the flyby pipeline's flight, bit for bit (issues 31, 40).

Every flight goes through :func:`ideas_hpc.flyby.views.flight_views`, which picks the
first compiled variant of the closed loop whose capabilities cover it: the 64-lane
loop, the scalar one-pass loop, or the batched loop of ``simulate_attitude`` (the
pipeline's, time series and all). Each is pinned here against the batched one."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.attitude.torque_terms import ConstantTorque
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.flyby import views
from ideas_hpc.flyby.camera import usable_mask
from ideas_hpc.flyby.flight import Perturbation, open_loop_views
from ideas_hpc.flyby.views import FlightPlan, closed_loop_for, flight_start, flight_views
from ideas_hpc.montecarlo.scenario_rows import RowEngine, full_rows
from ideas_hpc.montecarlo.scenarios import draw_world, grid_theta, nominal_start, row_engine
from ideas_hpc.base.seeds import SCENARIO_STREAM

ROOT = Path(__file__).resolve().parent.parent
# the main job's model (closed loop from the reference, usable images) on a short pass
MAIN = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3",
        "dynamics.srp=false"]
# errors large enough that the first images are unsettled and get blinded
WIDE = ["monte_carlo.sigma_attitude_deg=0.3"]


def _main(sets=()):
    c = load(ROOT / "campaigns" / "eros-design.toml", MAIN + list(sets))
    return c, setup_from_campaign(c), c.config.monte_carlo


@pytest.mark.parametrize("sets,torque,lanes", [
    (WIDE, None, True), (WIDE, None, False),
    (WIDE + ["monte_carlo.sigma_misalignment_deg=0.0"], None, True),
    (WIDE, (2e-6, -1e-6, 5e-7), True), (WIDE, "no-imaging", True)],
    ids=["misaligned", "misaligned-scalar", "aligned", "disturbed", "every-image"])
def test_one_pass_flight_is_the_pipeline_flight(sets, torque, lanes, monkeypatch):
    c, setup, mc = _main(sets)
    if torque == "no-imaging":  # a setup without the usable-image test
        setup = setup.with_(imaging=None)
    elif torque is not None:    # a disturbance torque the controller is not told
        setup = setup.with_(torques=(ConstantTorque(torque),))
    if not lanes:               # the scalar loop where the lanes would fly
        monkeypatch.setattr(views, "CLOSED_LOOPS",
                            [v for v in views.CLOSED_LOOPS if v.name != "lanes"])
    theta = grid_theta(np.deg2rad(4.0))    # 90: a full block of 64 lanes and a partial one
    r0, v0 = nominal_start(setup, theta)
    buffers: dict = {}
    blinded = 0
    expect = "lanes" if lanes and torque in (None, "no-imaging") else "scalar"
    for s in range(3):
        pert = Perturbation(**draw_world(mc, setup, theta, 11, SCENARIO_STREAM, s))
        assert closed_loop_for(setup, flight_start(setup, pert, theta.size), False).name == expect
        assert closed_loop_for(setup, flight_start(setup, pert, theta.size), True).name == "batch"
        ref = flight_views(setup, theta, None, r0, v0, pert)                 # the pipeline's
        one = flight_views(setup, theta, None, r0, v0, pert,
                           plan=FlightPlan(series=False, buffers=buffers))
        assert ref.attitude is not None and one.attitude is None and one.dcm_BT is None
        assert one.r_img_T.tobytes() == np.ascontiguousarray(ref.r_img_T).tobytes()
        assert one.imaging_BT.tobytes() == np.ascontiguousarray(ref.imaging_BT).tobytes()
        assert one.imaging_BT is buffers["dcm"]
        ok = usable_mask(setup, ref.attitude)
        if ok is None:                      # no usable-image test: every image counts
            assert buffers["usable"].all()
            continue
        np.testing.assert_array_equal(buffers["usable"], ok)
        blinded += int((~ok).sum())
    assert blinded > 0 or setup.imaging is None     # the blinding was exercised


def test_one_pass_bank_rows_are_the_flown_rows():
    # rows of the bank's path == rows of the pipeline's flight (fast and full) on 6 scenarios
    c, setup, mc = _main(WIDE)
    theta = grid_theta(np.deg2rad(15.0))
    eng = row_engine(setup, theta, mc, 5, SCENARIO_STREAM)
    seen = 0
    for s in range(6):
        pert = Perturbation(**draw_world(mc, setup, theta, 5, SCENARIO_STREAM, s))
        eng.one_pass = True
        new = eng.rows(*eng.flight(pert, reuse=True))
        eng.one_pass = False
        old = eng.rows(*eng.flight(pert))
        full = full_rows(setup, theta, None, eng.r0_T, eng.v0_T, pert)
        np.testing.assert_array_equal(new, full)
        np.testing.assert_array_equal(old, full)
        seen += int(new.sum())
    assert seen > 0


@pytest.mark.parametrize("sets", [['attitude.mode="ideal"'],
                                  ['monte_carlo.attitude_start="paper"']],
                         ids=["ideal", "paper-start"])
def test_flights_the_one_pass_loops_do_not_cover_take_the_batched_loop(sets):
    c, setup, mc = _main(sets)
    theta = grid_theta(np.deg2rad(30.0))
    pert = Perturbation(**draw_world(mc, setup, theta, 3, SCENARIO_STREAM, 1))
    if setup.attitude.closed_loop:      # an absolute start: only the batched loop flies it
        assert closed_loop_for(setup, flight_start(setup, pert, theta.size), False).name == \
            "batch"
    eng = row_engine(setup, theta, mc, 3, SCENARIO_STREAM)
    np.testing.assert_array_equal(eng.rows(*eng.flight(pert, reuse=True)),
                                  full_rows(setup, theta, None, eng.r0_T, eng.v0_T, pert))


def test_the_engines_nominal_flight_is_the_pipelines():
    # positions at the images only, the same bits (body tracking, which needs an
    # encounter, takes the pipeline)
    c, setup, mc = _main()
    theta = grid_theta(np.deg2rad(30.0))
    r0, v0 = nominal_start(setup, theta)
    r_ref, dcm_ref, _, _ = open_loop_views(setup.with_(attitude_mode="ideal"), theta, None, r0,
                                           v0, Perturbation())
    r, dcm = RowEngine(setup, theta, r0, v0)._nominal_flight()
    assert r.tobytes() == np.ascontiguousarray(r_ref).tobytes()
    assert dcm.tobytes() == np.ascontiguousarray(dcm_ref).tobytes()
