"""Where the closed loop starts and which images count (SPEC section 7d, issue 29 item 1).

Oracles: the ideal-tracking pipeline's camera (an independent computation of the
reference of each geometry), the controller's own error at t = 0, a long run of
the loop against the acquisition split in two, hand-computed smear limits, and
the geometry of a camera looking away from the body.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from ideas_hpc.attitude import initial_conditions, simulate_attitude
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.core.attitude.mrp import prv_from_mrp
from ideas_hpc.base.errors import InputError
from ideas_hpc.flyby.camera import discarded_images
from ideas_hpc.flyby.flight import Perturbation, fly_open_loop
from ideas_hpc.flyby.usable import ImageUse, blind, ifov_rad, usable_images
from ideas_hpc.mapping.coverage import compute_coverage
from ideas_hpc.montecarlo.dispersions import draw_sample
from ideas_hpc.montecarlo.sample import design_nominal, fly_sample

ROOT = Path(__file__).resolve().parent.parent
ENCOUNTER = ROOT / "campaigns" / "eros-fast-encounter.toml"
DESIGN = ROOT / "campaigns" / "eros-design-nominal.toml"
# the reference start (the fast encounter campaign counts every image: its file's start is
# the paper's)
SIMULATED = ['body.name="ellipsoid"', 'attitude.mode="simulated"',
             'monte_carlo.attitude_start="reference"']
PAPER_SHORT = ["flyby.tf_s=60", "flyby.z_start_km=-3", "flyby.z_stop_km=3",
               "dynamics.srp=false"]
THETA = np.array([0.3, 2.0, 4.0])


def _angle_deg(a, b):
    """Rotation angle between DCMs ``a`` and ``b`` (..., 3, 3), deg."""
    c = np.einsum("...ij,...kj->...ik", a, b)
    tr = np.clip((np.trace(c, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)
    return np.degrees(np.arccos(tr))


def _setup(path, sets):
    c = load(path, SIMULATED + list(sets))
    return c, setup_from_campaign(c)


def _on_reference(n):
    z = np.zeros((n, 3))
    return Perturbation(ics_reference=(z, z.copy(), z.copy()))


@pytest.mark.parametrize("path,sets", [
    (ENCOUNTER, []),                                            # tilted 45 deg, 10 km/s
    (ENCOUNTER, ['attitude.maneuver="track"']),                  # body tracking
    (DESIGN, PAPER_SHORT),                                       # the paper's pass
    (DESIGN, PAPER_SHORT + ['attitude.maneuver="fov"']),          # sweeping (rate at t0)
], ids=["encounter", "encounter-track", "paper", "paper-fov"])
def test_reference_start_is_the_ideal_camera(path, sets):
    # No attitude error: the closed loop's first image is the ideal camera's first
    # image (computed by the ideal-tracking path), and stays on it
    c, setup = _setup(path, sets)
    periods = None if setup.maneuver.name != "fov" else np.full(THETA.size, 120.0)
    nom = design_nominal(setup, THETA, periods)
    sim = fly_open_loop(setup, THETA, periods, nom.r0_T, nom.v0_T, _on_reference(THETA.size))
    ideal = fly_open_loop(setup.with_(attitude_mode="ideal"), THETA, periods, nom.r0_T,
                          nom.v0_T, Perturbation())
    assert _angle_deg(sim.dcm_BT[:, 0], ideal.dcm_BT[:, 0]).max() < 1e-5
    assert _angle_deg(sim.dcm_BT, ideal.dcm_BT).max() < 0.01
    assert np.abs(sim.attitude.omega_error[0, :, 0]).max() < 1e-9


def test_tilted_encounter_starts_within_the_dispersion():
    # The default start (attitude_dispersion on, reference): the controller's own
    # error at t = 0 is of the dispersion's scale, far below the 45 deg tilt of the
    # pass; with the dispersion off the swarm maps what the ideal nominal maps
    c, setup = _setup(ENCOUNTER, [])
    mc = c.config.monte_carlo
    assert mc.attitude_start == "reference" and mc.attitude_dispersion
    nom = design_nominal(setup, THETA, None)
    errs = []
    for k in range(4):
        _, pert = draw_sample(mc, c.config.seed, k, THETA, setup)
        out = fly_sample(setup, nom, Perturbation(**pert))
        errs.append(4.0 * np.arctan(np.linalg.norm(out["sigma_error"][:, 0], axis=-1)))
    errs = np.degrees(np.concatenate(errs))
    assert errs.max() < 6.0 * math.degrees(mc.sigma_attitude_rad) and errs.max() > 0.0
    off = dataclasses.replace(mc, attitude_dispersion=False)
    _, pert = draw_sample(off, c.config.seed, 0, THETA, setup)
    pert = Perturbation(**{**pert, "position_error_T": None, "velocity_error_T": None,
                           "misalignment_prv": None, "params_override": None})
    # the start alone: every image counted (no usable-image test), in both flights
    flown = fly_sample(setup.with_(imaging=None), nom, pert)
    ideal = fly_open_loop(setup.with_(attitude_mode="ideal", imaging=None), THETA, None,
                          nom.r0_T, nom.v0_T, Perturbation())
    assert ideal.coverage.coverage > 0.1
    assert abs(flown["coverage"] - ideal.coverage.coverage) < 0.005
    # with the usable-image test: the swarm frame is fixed in N, and at 10 km/s the scene
    # crosses it by tens of pixels in an exposure (SPEC 7d): every image is smeared
    sharp = fly_sample(setup, nom, pert)
    assert sharp["coverage"] == 0.0
    assert (sharp["images_discarded_smear"] == setup.image_times.size).all()


def test_reference_draws_have_their_declared_laws():
    c, setup = _setup(DESIGN, PAPER_SHORT)
    mc = dataclasses.replace(c.config.monte_carlo, sigma_attitude_rad=math.radians(0.05),
                             sigma_rate_rad_s=2e-4)
    prv, w = [], []
    for k in range(1500):
        _, pert = draw_sample(mc, 5, k, THETA, setup)
        s, om, wheels = pert["ics_reference"]
        assert not np.any(wheels)
        prv.append([prv_from_mrp(np.ascontiguousarray(v)) for v in s])
        w.append(om)
    for x, sigma in ((np.ravel(prv), mc.sigma_attitude_rad), (np.ravel(w), mc.sigma_rate_rad_s)):
        assert abs(x.std() - sigma) < 5 * sigma / np.sqrt(2 * x.size)
        assert stats.kstest(x / sigma, "norm").pvalue > 1e-4


def test_paper_start_is_the_papers_draw():
    c, setup = _setup(DESIGN, PAPER_SHORT + ['monte_carlo.attitude_start="paper"'])
    assert setup.imaging is None                 # every image counts, as in the paper
    for k in (0, 3):
        v, pert = draw_sample(c.config.monte_carlo, 9, k, THETA, setup)
        for got, want in zip(pert["ics"], initial_conditions(9, k, THETA.size)):
            np.testing.assert_array_equal(got, want)
        assert "ics_reference" not in pert and "acquisition_s" not in pert


def test_acquisition_is_the_long_run_split_at_the_window():
    # Nadir pointing is invariant under the spin (module doc of attitude.start):
    # flying the acquisition and then the window from the error state reached
    # starts the window with the error of one uninterrupted run at that time
    th = np.array([0.2, 2.9])
    spin, acq = 3.3e-4, 300.0
    s0, w0, W0 = initial_conditions(4, 0, th.size)
    whole = simulate_attitude(th, spin, acq + 10.0, sigma0=s0, omega0=w0, wheel0=W0)
    split = simulate_attitude(th, spin, 10.0, sigma0=s0, omega0=w0, wheel0=W0,
                              acquisition_s=acq)
    i = int(round(acq / 0.1))                     # dt 0.1 s, every step kept
    np.testing.assert_allclose(split.sigma_error[0, :, 0], whole.sigma_error[0, :, i],
                               atol=1e-12)
    np.testing.assert_allclose(split.omega_error[0, :, 0], whole.omega_error[0, :, i],
                               atol=1e-12)
    # converged before the window: far inside the default settle limit, no smear
    start_err = 4.0 * np.arctan(np.linalg.norm(split.sigma_error[0, :, 0], axis=-1))
    assert np.degrees(start_err).max() < 0.01
    assert np.degrees(4.0 * np.arctan(np.linalg.norm(whole.sigma_error[0, :, 0],
                                                     axis=-1))).min() > 1.0


def test_image_rate_and_error_are_the_state_at_the_images():
    th = np.array([0.2, 2.9])
    s0, w0, W0 = initial_conditions(2, 0, th.size)
    r = simulate_attitude(th, 3.3e-4, 1.0, sigma0=s0, omega0=w0, wheel0=W0, image_dt=0.1,
                          decimate=1)
    np.testing.assert_allclose(r.image_rate[0, :, 0], np.linalg.norm(w0, axis=1), rtol=1e-14)
    np.testing.assert_allclose(r.image_error[0],
                               4.0 * np.arctan(np.linalg.norm(r.sigma_error[0], axis=-1)),
                               rtol=1e-14)


def test_smear_limit_by_hand():
    # IFOV 2^-16 rad, exposure 2^-6 s, 1 pixel: the largest usable rate is 2^-10 rad/s
    use = ImageUse(ifov_rad=2.0 ** -16, exposure_s=2.0 ** -6, smear_pixels=1.0,
                   settle_rad=math.radians(0.1))
    assert use.max_rate_rad_s == 2.0 ** -10
    rate = np.array([[0.5, 1.0, 1.5, 40.0]]) * 2.0 ** -10   # settled, boundary, slewing x 2
    err = np.array([[0.0, 0.0, 0.0, 0.0]])
    ok, smear, settle = usable_images(use, rate, err)
    np.testing.assert_array_equal(ok, [[True, True, False, False]])
    assert smear.tolist() == [2] and settle.tolist() == [0]
    ok, smear, settle = usable_images(use, rate[:, :1].repeat(3, 1),
                                      np.radians([[0.05, 0.1, 0.2]]))
    np.testing.assert_array_equal(ok, [[True, True, False]])
    assert smear.tolist() == [0] and settle.tolist() == [1]
    # two pixels allowed: the 1.5-pixel image is accepted
    ok, _, _ = usable_images(dataclasses.replace(use, smear_pixels=2.0), rate, 0 * rate)
    np.testing.assert_array_equal(ok, [[True, True, True, False]])


def test_ifov_sources():
    assert ifov_rad(0.01, pixels_across=1000) == 2e-5
    assert ifov_rad(0.01, pixel_pitch_m=5e-6, focal_length_m=0.5) == 1e-5
    assert ifov_rad(0.01, wavelength_m=0.55e-6, aperture_m=0.08) == 0.55e-6 / 0.08
    with pytest.raises(InputError) as e:
        ImageUse(ifov_rad=1e-5, exposure_s=0.0)
    assert e.value.field == "exposure_s"


def test_blind_camera_sees_nothing():
    c, setup = _setup(DESIGN, PAPER_SHORT)
    nom = design_nominal(setup, THETA, None)
    f = fly_open_loop(setup.with_(attitude_mode="ideal"), THETA, None, nom.r0_T, nom.v0_T,
                      Perturbation())
    assert f.coverage.observed.any()
    keep = np.zeros(f.dcm_BT.shape[:2], dtype=bool)
    keep[0, -1] = True                          # one image of spacecraft 0 left
    dcm = blind(f.dcm_BT, f.r_img_T, keep, setup.body.shape.r_max)
    for mode in ("paper", "exact"):
        cov = compute_coverage(setup.body.shape, f.r_img_T, dcm, setup.image_times,
                               setup.eta_rad, setup.near_m, setup.far_m,
                               options=dataclasses.replace(setup.coverage, mode=mode))
        alone = compute_coverage(setup.body.shape, f.r_img_T[:1, -1:], f.dcm_BT[:1, -1:],
                                 setup.image_times[-1:], setup.eta_rad, setup.near_m,
                                 setup.far_m, options=dataclasses.replace(setup.coverage,
                                                                          mode=mode))
        np.testing.assert_array_equal(cov.observed, alone.observed)


def test_short_acquisition_discards_the_slewing_images():
    # A random attitude one second before the window, the usable-image test on:
    # the slewing first images are discarded, the settled last ones kept; the
    # counts reach the Monte Carlo sample
    c, setup = _setup(DESIGN, ["flyby.tf_s=180", "flyby.z_start_km=-9", "flyby.z_stop_km=9",
                               "dynamics.srp=false", 'monte_carlo.attitude_start="acquisition"',
                               "monte_carlo.acquisition_s=1.0"])
    nom = design_nominal(setup, THETA, None)
    _, pert = draw_sample(c.config.monte_carlo, 1, 0, THETA, setup)
    out = fly_sample(setup, nom, Perturbation(**pert))
    n_img = setup.image_times.size
    smear, settle = out["images_discarded_smear"], out["images_discarded_settle"]
    assert smear.shape == settle.shape == (THETA.size,)
    assert np.all(smear > 0) and np.all(settle > 0) and np.all(settle < n_img)
    f = fly_open_loop(setup, THETA, None, nom.r0_T, nom.v0_T, Perturbation(**pert))
    found = discarded_images(setup, f.attitude)
    np.testing.assert_array_equal(found[0], smear)
    rate = f.attitude.image_smear_rate[0]      # the scene's image rate (SPEC 7d)
    assert np.all(rate[:, 0] * setup.imaging.exposure_s
                  > setup.imaging.smear_pixels * setup.imaging.ifov_rad)


@pytest.mark.parametrize("key,value,field", [
    ("monte_carlo.attitude_start", '"tumbling"', "monte_carlo.attitude_start"),
    ("monte_carlo.acquisition_s", "-1.0", "monte_carlo.acquisition_s"),
    ("monte_carlo.sigma_attitude_deg", "-0.1", "monte_carlo.sigma_attitude_deg"),
    ("instrument.exposure_ms", "0.0", "instrument.exposure_ms"),
    ("instrument.pixels_across", "0", "instrument.pixels_across"),
    ("instrument.settle_deg", "-1.0", "instrument.settle_deg"),
])
def test_bad_keys_name_their_field(key, value, field):
    with pytest.raises(InputError) as e:
        load(DESIGN, [f"{key}={value}"])
    assert e.value.field == field


def test_acquisition_needs_a_duration():
    with pytest.raises(InputError) as e:
        load(DESIGN, ['attitude.mode="simulated"', 'monte_carlo.attitude_start="acquisition"',
                      "monte_carlo.acquisition_s=0"])
    assert e.value.field == "monte_carlo.acquisition_s"


def test_nominal_candidate_masks_start_on_the_reference():
    # The designers' simulated candidate masks fly the closed loop from the
    # reference (no draw): they are the ideal-tracking masks; the paper's start
    # (random, seeded) differs from them
    from ideas_hpc.design.candidates import candidate_masks

    keys = [(t, 0.0, i) for i, t in enumerate(np.deg2rad([0.0, 50.0, 130.0, 250.0]))]
    c, setup = _setup(DESIGN, PAPER_SHORT)
    assert setup.attitude_start == "reference"
    ideal = candidate_masks(setup.with_(attitude_mode="ideal"), keys)
    np.testing.assert_array_equal(candidate_masks(setup, keys), ideal)
    paper = candidate_masks(setup.with_(attitude_start="paper", imaging=None), keys)
    assert (paper != ideal).any()


def test_blinding_inside_the_bounding_sphere_past_the_waist():
    """A navigation error can put a spacecraft inside the bounding sphere of an elongated
    body, beside its waist (``ideas-hpc study`` at a 100 km sigma, 2026-12-07): the radial
    camera would see the body's ends there. The blinded camera must have every vertex
    behind it (``q_z < 0``, what every coverage mode needs), and the coverage sees nothing;
    inside the body's hull the error names the field."""
    from ideas_hpc.body.bodies import load_body
    from ideas_hpc.flyby.usable import separating_axis

    shape = load_body("ellipsoid", resolution=2).shape
    v = shape.vertices_T
    half = np.ptp(v, axis=0) / 2
    long, waist = int(np.argmax(half)), int(np.argmin(half))
    r = np.zeros(3)
    # off both axes, outside the hull ((0.6)^2 + (1.2)^2 > 1), well inside the sphere
    r[long], r[waist] = 0.6 * half[long], 1.2 * half[waist]
    assert np.linalg.norm(r) < shape.r_max
    radial = r / np.linalg.norm(r)
    assert np.max((v - r) @ radial) > 0      # the radial camera would see the body's ends
    assert separating_axis(np.zeros(3), v) is None              # the centre: inside the hull
    r_img = np.stack([r, 3 * shape.r_max * radial])[None]       # (1, 2, 3): in, out
    dcm = np.broadcast_to(np.eye(3), (1, 2, 3, 3)).copy()
    dcm_b = blind(dcm, r_img, np.zeros((1, 2), dtype=bool), shape.r_max, v)
    for i in range(2):
        q_z = (v - r_img[0, i]) @ dcm_b[0, i, 2]
        assert np.max(q_z) < 0, i
        np.testing.assert_allclose(dcm_b[0, i] @ dcm_b[0, i].T, np.eye(3), atol=1e-12)
        assert np.linalg.det(dcm_b[0, i]) > 0
    np.testing.assert_allclose(dcm_b[0, 1, 2], radial)          # outside: radial as before
    cov = compute_coverage(shape, r_img, dcm_b, np.array([0.0, 1.0]), np.radians(60.0), 1.0,
                           1e9)
    assert not cov.observed.any()
    with pytest.raises(InputError) as e:                         # no vertices: no way to tell
        blind(dcm, r_img, np.zeros((1, 2), dtype=bool), shape.r_max)
    assert e.value.field == "r_img_T"
    r_in = r_img.copy()
    r_in[0, 0] = 0.0
    with pytest.raises(InputError) as e:
        blind(dcm, r_in, np.zeros((1, 2), dtype=bool), shape.r_max, v)
    assert e.value.field == "r_img_T" and "convex hull" in str(e.value)
