"""Navigation errors at a real encounter (SPEC 7f): the B-plane, the TCA shift, the presets.

Oracles: the B-plane frame of a velocity along +x worked by hand; the covariance of an
ellipse with semi-axes ``a, b`` at angle ``theta`` written out (``Sigma_TT = a^2 cos^2 +
b^2 sin^2`` ...) and the chi-square law of its Mahalanobis distance; a brute-force
search of the closest approach of the straight track to the displaced target; the
published 3-sigma figures divided by 3.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import optimize, stats

from ideas_hpc.base import seeds
from ideas_hpc.flyby.navigation import (ARROKOTH, DINKINESH, LUTETIA, NavigationError,
                                        bplane_frame, draw_navigation, member_offsets_N,
                                        target_offset_N)

DEG = math.pi / 180.0


def test_bplane_frame_by_hand_and_in_general():
    f = bplane_frame([10e3, 0.0, 0.0])
    np.testing.assert_allclose(f, [[1, 0, 0], [0, -1, 0], [0, 0, -1]], atol=1e-15)
    v = np.array([3.0, -7.0, 2.0])
    s, t, r = bplane_frame(v)
    np.testing.assert_allclose(np.vstack([s, t, r]) @ np.vstack([s, t, r]).T, np.eye(3),
                               atol=1e-14)
    assert np.dot(np.cross(s, t), r) == pytest.approx(1.0)
    assert abs(t[2]) < 1e-15 and r[2] < 0.0           # T in the ecliptic, R toward its south
    np.testing.assert_allclose(s, v / np.linalg.norm(v))
    s, t, r = bplane_frame([0.0, 0.0, 5.0])           # along the pole: k = +x instead
    assert np.dot(t, [1.0, 0.0, 0.0]) == pytest.approx(0.0, abs=1e-15)


def test_draws_follow_the_configured_ellipse():
    a, b, th = 30e3, 8e3, 35.0 * DEG
    err = NavigationError(a, b, th, sigma_tca_s=4.0, sigma_member_m=50.0)
    d = [draw_navigation(err, seeds.navigation_rng(3, 0, m), 4) for m in range(20000)]
    xy = np.array([[x.xi_m, x.eta_m] for x in d])
    c, s = math.cos(th), math.sin(th)
    cov = np.array([[a * a * c * c + b * b * s * s, (a * a - b * b) * s * c],
                    [(a * a - b * b) * s * c, a * a * s * s + b * b * c * c]])
    np.testing.assert_allclose(err.covariance_TR_m2, cov, rtol=1e-12)
    m2 = np.einsum("ij,jk,ik->i", xy, np.linalg.inv(cov), xy)
    assert stats.kstest(m2, stats.chi2(2).cdf).pvalue > 1e-3
    emp = np.cov(xy.T)
    # sample covariance within ~4 standard errors (var of s_ij ~ (S_ii S_jj + S_ij^2) / n)
    se = np.sqrt((np.outer(np.diag(cov), np.diag(cov)) + cov ** 2) / len(xy))
    assert np.all(np.abs(emp - cov) < 4.0 * se)
    w, vec = np.linalg.eigh(emp)
    angle = math.atan2(vec[1, 1], vec[0, 1]) % math.pi
    assert angle == pytest.approx(th, abs=2.0 * DEG)
    dt = np.array([x.dt_tca_s for x in d])
    assert abs(dt.std() / 4.0 - 1.0) < 4.0 / math.sqrt(2 * dt.size)
    mem = np.concatenate([x.member_offsets_m for x in d])
    assert abs(mem.std() / 50.0 - 1.0) < 4.0 / math.sqrt(2 * mem.size)
    assert abs(np.corrcoef(dt, xy[:, 0])[0, 1]) < 4.0 / math.sqrt(dt.size)


def test_target_offset_moves_the_closest_approach():
    v = np.array([9e3, 4e3, -2e3])
    speed = np.linalg.norm(v)
    s, t, r = bplane_frame(v)
    b_pred = 500e3 * (0.6 * t + 0.8 * r)              # planned miss vector, in the B-plane
    err = NavigationError(40e3, 20e3, 0.3, sigma_tca_s=5.0, sigma_member_m=0.0)
    for m in range(5):
        draw = draw_navigation(err, seeds.navigation_rng(9, 1, m), 0)
        delta = target_offset_N(draw, v)
        # spacecraft relative to the true target: b_pred + v t - delta, t from the predicted TCA
        dist = lambda tt: np.linalg.norm(b_pred + v * tt - delta)  # noqa: E731
        res = optimize.minimize_scalar(dist, bracket=(-100.0, 100.0), tol=1e-12)
        assert res.x == pytest.approx(draw.dt_tca_s, abs=1e-4)
        miss = b_pred + v * res.x - delta
        np.testing.assert_allclose(miss, b_pred - draw.xi_m * t - draw.eta_m * r, atol=1e-2)
        plane = target_offset_N(draw, v, along_track=False)
        np.testing.assert_allclose(delta - plane, speed * draw.dt_tca_s * s, atol=1e-6)


def test_members_share_the_common_error():
    err = NavigationError(10e3, 10e3, 0.0, sigma_tca_s=1.0, sigma_member_m=100.0)
    draw = draw_navigation(err, seeds.navigation_rng(1, 2, 3), 5)
    v = [0.0, 10e3, 0.0]
    rel = member_offsets_N(draw, v)
    np.testing.assert_allclose(rel - draw.member_offsets_m,
                               np.tile(-target_offset_N(draw, v), (5, 1)))


def test_presets_are_the_published_figures_at_one_sigma():
    km = 1e3
    assert (LUTETIA.sigma_major_m, LUTETIA.sigma_minor_m) == pytest.approx((32 * km / 3,
                                                                            16 * km / 3))
    assert LUTETIA.sigma_tca_s == pytest.approx(7.30 / 3) and LUTETIA.speed_m_s == 15e3
    assert (ARROKOTH.sigma_major_m, ARROKOTH.sigma_minor_m) == pytest.approx((320 * km / 3,
                                                                              120 * km / 3))
    assert ARROKOTH.sigma_tca_s == pytest.approx(140.0 / 3) and ARROKOTH.speed_m_s == 14.4e3
    assert DINKINESH.sigma_major_m == pytest.approx(160 * km / 3)
    assert DINKINESH.speed_m_s == 4.5e3
    for p in (LUTETIA, ARROKOTH, DINKINESH):
        assert p.update and p.source
    late = LUTETIA.scaled(1e3)
    assert late.sigma_minor_m / late.sigma_major_m == pytest.approx(0.5)
    with pytest.raises(ValueError, match="sigma_minor_m"):
        NavigationError(1.0, 2.0)
