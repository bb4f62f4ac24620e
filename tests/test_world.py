"""The World record and the one flight path through it (issue 40).

A scenario's world carries the body (shape, pole, spin, phase, gravity), the Sun,
the encounter and the force model; every flight goes through
:func:`ideas_hpc.flyby.views.flight_views` with one. Checked against independent
truths: the geometry of a pole tilted from the orbit normal, and a setup whose body
carries the world's parameters itself (no World, no per-world statics).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from ideas_hpc.base.errors import InputError
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.dynamics.force_model import world_parameters
from ideas_hpc.flyby import world as _world
from ideas_hpc.flyby.flight import Perturbation
from ideas_hpc.flyby.views import FlightPlan, flight_views
from ideas_hpc.montecarlo.scenarios import draw_world, grid_theta, nominal_start
from ideas_hpc.base.seeds import SCENARIO_STREAM

ROOT = Path(__file__).resolve().parent.parent
SHORT = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3",
         "monte_carlo.sigma_attitude_deg=0.3"]


@pytest.fixture(scope="module")
def main():
    c = load(ROOT / "campaigns" / "eros-design.toml", SHORT)
    return setup_from_campaign(c), c.config.monte_carlo


def test_a_worlds_parameters_are_one_list(main):
    setup, _ = main
    world = setup.world
    assert world.params is setup.body.params and world.flown(setup) is setup
    for name in world_parameters():          # each is accepted by name
        value = 0.5 if name in ("reflectivity", "orbit_e") else 1.0
        if name in ("pole_ra", "pole_dec"):  # Eros' preset has none: both together
            continue
        assert dict(world.perturbed({name: value}).parameters)[name] == value
    with pytest.raises(InputError) as err:
        world.perturbed({"pole_tilt": 0.1})
    assert err.value.field == "params_override.pole_tilt"
    with pytest.raises(InputError) as err:
        world.perturbed({"pole_ra": 0.1})
    assert err.value.field == "params_override.pole_ra"
    with pytest.raises(InputError) as err:
        world.perturbed({"spin_period": -1.0})
    assert err.value.field == "params_override.spin_period"
    tilted = world.perturbed({"pole_ra": 0.1, "pole_dec": 1.2, "reflectivity": 0.3})
    assert tilted.pole_rad == (0.1, 1.2)
    assert tilted.flown(setup).force_model.reflectivity == 0.3
    assert tilted.flown(setup).body.params.pole_dec == 1.2


def test_the_sun_of_a_world_follows_its_pole(main):
    # Independent geometry: the Sun lies in the orbit plane, so about the orbit normal
    # h (the pole of a body without one) its T-frame z component is 0; about a pole
    # tilted by delta from h along u1 or along u2 (u1, u2, h orthonormal) the two
    # components are sin(delta) (s . u1) and sin(delta) (s . u2), whose squares sum
    # to sin(delta)^2 at every time.
    setup, _ = main
    world = setup.world
    times = np.linspace(0.0, 3.0e7, 7)       # most of a year of the heliocentric orbit
    assert np.max(np.abs(world.sun_T(times)[:, 2])) < 1e-12
    ra, dec = world.pole_rad
    h = np.array([math.cos(dec) * math.cos(ra), math.cos(dec) * math.sin(ra), math.sin(dec)])
    u1 = np.cross(h, [0.0, 0.0, 1.0])
    u1 /= np.linalg.norm(u1)
    u2 = np.cross(h, u1)
    delta = math.radians(20.0)
    z = []
    for u in (u1, u2):
        p = math.cos(delta) * h + math.sin(delta) * u
        tilted = world.perturbed({"pole_ra": math.atan2(p[1], p[0]),
                                  "pole_dec": math.asin(p[2])})
        z.append(tilted.sun_T(times)[:, 2])
    np.testing.assert_allclose(z[0] ** 2 + z[1] ** 2, math.sin(delta) ** 2, rtol=1e-9)


def test_a_world_flies_what_a_body_with_its_parameters_flies(main):
    # A world with another spin (and gravity) flown by the one path with per-world
    # statics (the lanes) is, bit for bit, the batched loop's flight of a setup whose
    # body carries those parameters itself.
    setup, mc = main
    theta = grid_theta(np.deg2rad(30.0))
    r0, v0 = nominal_start(setup, theta)
    pert = Perturbation(**draw_world(mc, setup, theta, 3, SCENARIO_STREAM, 0))
    spin = {"spin_period": setup.body.params.spin_period * 0.8, "mu": setup.body.params.mu * 1.1}
    world = setup.world.perturbed(dict(pert.params_override, **spin))
    assert world.attitude_key != setup.world.attitude_key      # its own closed-loop statics
    assert setup.world.perturbed({"mu": 1.0}).attitude_key == setup.world.attitude_key
    one = flight_views(setup, theta, None, r0, v0, pert, world=world,
                       plan=FlightPlan(series=False))
    params = dataclasses.replace(setup.body.params, **{k: v for k, v in world.parameters
                                                       if k != "reflectivity"})
    own = setup.with_(body=dataclasses.replace(setup.body, params=params),
                      force_model=dataclasses.replace(setup.force_model,
                                                      reflectivity=world.flown_force_model
                                                      .reflectivity))
    ref = flight_views(own, theta, None, r0, v0, dataclasses.replace(pert, params_override=None))
    assert one.r_img_T.tobytes() == np.ascontiguousarray(ref.r_img_T).tobytes()
    assert one.imaging_BT.tobytes() == np.ascontiguousarray(ref.imaging_BT).tobytes()
    nominal = flight_views(setup, theta, None, r0, v0, pert, plan=FlightPlan(series=False))
    assert nominal.imaging_BT.tobytes() != one.imaging_BT.tobytes()    # the spin was flown


def test_per_world_statics_are_kept_by_what_they_read(monkeypatch):
    built = []
    monkeypatch.setattr(_world, "_STATICS", _world.OrderedDict())
    for key in ("a", "b", "a", "c", "a"):
        _world.cached_static(("t", key), lambda: built.append(1) or len(built))
    assert len(built) == 3
    assert _world.cached_static(("t", "a"), lambda: -1) == 1
