"""Straight-pass line-of-sight kinematics and the wheels' limits (SPEC 7f).

Oracles: the line-of-sight angle from the geometry itself (the angle between the
direction at ``t`` and at TCA), finite differences of it, a dense grid for the peak
and the saturation windows, and numbers worked by hand:

10 km/s at 500 km: ``omega_max = v/d = 0.02 rad/s``; ``alpha_max = (3 sqrt 3 / 8)
(v/d)^2 = 0.649519 * 4e-4 = 2.598e-4 rad/s^2`` at ``t = d / (sqrt 3 v) = 28.87 s``.
The paper's spacecraft (4 kg, 10 x 10 x 30 cm, camera along the 30 cm side) turns
about a 10 cm axis: ``I = 4/12 (0.1^2 + 0.3^2) + 2 (0.24 * 0.029^2 / 4) = 0.0333333 +
0.0001009 = 0.0334343 kg m^2 (0.03343425)``, so it needs ``h = 6.687e-4 N m s`` (limit 0.05) and
``u = 8.687e-6 N m`` (limit 0.007): it follows. At 5 km the rate is 2 rad/s:
``h = 0.0669 > 0.05`` for ``|t| < sqrt(v d I / h_max - d^2) / v = 0.2904 s``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ideas_hpc.attitude.spacecraft import SpacecraftModel
from ideas_hpc.flyby.pass_rates import (TerminalTracking, follow_check, los_acceleration_rad_s2,
                                        los_rate_rad_s, peak_los_acceleration_rad_s2,
                                        peak_los_rate_rad_s, pointing_bias_rad,
                                        pointing_bias_small_rad)


def _geometric_angle(t, v, d):
    """Angle swept by the line of sight since TCA, from the positions (d, v t)."""
    p = np.stack([np.full_like(t, d), v * t], axis=-1)
    cos = p[..., 0] / np.linalg.norm(p, axis=-1)
    return np.sign(t) * np.arccos(np.clip(cos, -1.0, 1.0))


@pytest.mark.parametrize("v, d", [(10e3, 500e3), (15e3, 50e3), (4.5e3, 425e3)])
def test_rates_against_finite_differences_of_the_geometry(v, d):
    t = np.linspace(-3.0, 3.0, 13) * d / v + 0.37      # avoid t = 0 in the sign
    h = 1e-3 * d / v
    omega_fd = (_geometric_angle(t + h, v, d) - _geometric_angle(t - h, v, d)) / (2 * h)
    np.testing.assert_allclose(los_rate_rad_s(t, v, d), omega_fd, rtol=1e-6)
    alpha_fd = (los_rate_rad_s(t + h, v, d) - los_rate_rad_s(t - h, v, d)) / (2 * h)
    np.testing.assert_allclose(los_acceleration_rad_s2(t, v, d), alpha_fd, rtol=1e-5,
                               atol=1e-9 * (v / d) ** 2)
    # second differences of the angle itself
    a2 = (_geometric_angle(t + h, v, d) - 2 * _geometric_angle(t, v, d)
          + _geometric_angle(t - h, v, d)) / h ** 2
    np.testing.assert_allclose(los_acceleration_rad_s2(t, v, d), a2, rtol=1e-3,
                               atol=1e-6 * (v / d) ** 2)


def test_peaks_against_a_dense_grid_and_by_hand():
    v, d = 10e3, 500e3
    t = np.linspace(-200.0, 200.0, 400001)
    assert np.abs(los_rate_rad_s(t, v, d)).max() == pytest.approx(0.02, rel=1e-12)
    alpha = np.abs(los_acceleration_rad_s2(t, v, d))
    assert alpha.max() == pytest.approx(2.598076e-4, rel=1e-6)
    assert abs(t[np.argmax(alpha)]) == pytest.approx(28.8675, abs=1e-3)
    assert peak_los_rate_rad_s(v, d) == pytest.approx(0.02)
    assert peak_los_acceleration_rad_s2(v, d) == pytest.approx(alpha.max(), rel=1e-9)


def test_follow_check_by_hand():
    ok = follow_check(10e3, 500e3)
    assert ok.inertia_kg_m2 == pytest.approx(0.03343425, rel=1e-7)
    assert ok.momentum_peak_N_m_s == pytest.approx(6.687e-4, rel=1e-3)
    assert ok.torque_peak_N_m == pytest.approx(8.687e-6, rel=1e-3)
    assert ok.feasible and ok.lost_windows_s == ()
    close = follow_check(10e3, 5e3)
    assert not close.momentum_ok and not close.torque_ok
    assert close.momentum_window_s == pytest.approx((-0.2904, 0.2904), abs=1e-4)


@pytest.mark.parametrize("v, d", [(10e3, 5e3), (15e3, 20e3), (10e3, 30e3)])
def test_saturation_windows_against_a_dense_grid(v, d):
    sc = SpacecraftModel()
    chk = follow_check(v, d, sc)
    t = np.linspace(-20.0, 20.0, 2000001)
    dt = t[1] - t[0]
    inertia = chk.inertia_kg_m2
    for bad, windows in (
            (inertia * los_rate_rad_s(t, v, d) > sc.h_max_N_m_s,
             [chk.momentum_window_s] if chk.momentum_window_s else []),
            (inertia * np.abs(los_acceleration_rad_s2(t, v, d)) > sc.u_max_N_m,
             list(chk.torque_windows_s))):
        inside = np.zeros_like(bad)
        for a, b in windows:
            inside |= (t > a) & (t < b)
        edge = np.zeros_like(bad)
        for a, b in windows:
            edge |= (np.abs(t - a) < 2 * dt) | (np.abs(t - b) < 2 * dt)
        assert np.array_equal(bad[~edge], inside[~edge])
    assert chk.lost_windows_s or chk.feasible


def test_pointing_bias_and_terminal_tracking():
    rho, dperp = 100e3, 10e3
    bias = pointing_bias_rad([rho, 0.0, 0.0], [0.0, dperp, 0.0])
    assert float(bias) == pytest.approx(math.atan(0.1))                    # 5.71 deg
    assert math.degrees(pointing_bias_small_rad(dperp, rho)) == pytest.approx(5.7296, abs=1e-4)
    # a displacement along the line of sight does not bias the pointing
    assert float(pointing_bias_rad([rho, 0.0, 0.0], [5e3, 0.0, 0.0])) == 0.0
    tt = TerminalTracking(detect_pixels=5.0, centroid_sigma_rad=2e-5)
    r_det = tt.detection_range_m(16e3, 1e-5)
    assert r_det == pytest.approx(16e3 / 5e-5)                            # 320,000 km
    err = tt.pointing_error_rad([1e9, r_det * 1.01, r_det * 0.99, 1e5], 0.01, 16e3, 1e-5)
    np.testing.assert_array_equal(err, [0.01, 0.01, 2e-5, 2e-5])
