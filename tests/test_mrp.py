"""MRP kernels against independent truth: scipy's Rotation, textbook values
(Schaub & Junkins 2018, sec. 3.7), DCM algebra and finite differences."""

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from ideas_hpc.core.attitude import mrp

comp = st.floats(-3.0, 3.0, allow_nan=False)
vec = st.tuples(comp, comp, comp).map(lambda t: np.array(t, dtype=np.float64))
SET = settings(max_examples=300, deadline=None)


def _scipy_dcm(sigma):
    """[BN] from scipy: its matrix maps B->N components for a passive attitude, so transpose."""
    q = mrp.quat_from_mrp(sigma)
    return Rotation.from_quat([q[1], q[2], q[3], q[0]]).as_matrix().T


@SET
@given(vec)
def test_dcm_orthonormal_and_matches_scipy(s):
    c = mrp.dcm_from_mrp(s)
    assert np.allclose(c @ c.T, np.eye(3), atol=1e-12)
    assert np.isclose(np.linalg.det(c), 1.0, atol=1e-12)
    assert np.allclose(c, _scipy_dcm(s), atol=1e-12)


def test_textbook_value():
    # 90 deg about z: sigma = tan(22.5 deg) z; [BN] maps N's x axis to B's -y.
    s = np.array([0.0, 0.0, np.tan(np.pi / 8)])
    c = mrp.dcm_from_mrp(s)
    assert np.allclose(c @ np.array([1.0, 0, 0]), [0, -1, 0], atol=1e-15)
    # S&J Example 3.10-ish: round trip through the principal rotation vector.
    assert np.allclose(mrp.prv_from_mrp(s), [0, 0, np.pi / 2])


@SET
@given(vec)
def test_shadow_same_dcm(s):
    assume(np.linalg.norm(s) > 1e-3)
    assert np.allclose(mrp.dcm_from_mrp(s), mrp.dcm_from_mrp(mrp.mrp_shadow(s)), atol=1e-10)


@SET
@given(vec)
def test_dcm_roundtrip(s):
    back = mrp.mrp_from_dcm(mrp.dcm_from_mrp(s))
    assert np.linalg.norm(back) <= 1.0 + 1e-12
    assert np.allclose(mrp.dcm_from_mrp(back), mrp.dcm_from_mrp(s), atol=1e-10)
    assert np.allclose(back, mrp.mrp_switch(s), atol=1e-8) or \
        np.isclose(np.linalg.norm(back), 1.0, atol=1e-6)


@SET
@given(vec, vec)
def test_add_matches_dcm_product_and_sub_inverts(s1, s2):
    c = mrp.dcm_from_mrp(mrp.mrp_add(s1, s2))
    assert np.allclose(c, mrp.dcm_from_mrp(s2) @ mrp.dcm_from_mrp(s1), atol=1e-9)
    # add then subtract returns the input (as an attitude; the set is the short one)
    back = mrp.mrp_sub(mrp.mrp_add(s1, s2), s1)
    assert np.allclose(mrp.dcm_from_mrp(back), mrp.dcm_from_mrp(s2), atol=1e-9)
    assert np.allclose(back, mrp.mrp_switch(s2), atol=1e-7) or \
        np.isclose(np.linalg.norm(back), 1.0, atol=1e-6)
    # sub gives [BR] = [BN][RN]^T
    d = mrp.mrp_sub(s1, s2)
    assert np.allclose(mrp.dcm_from_mrp(d), mrp.dcm_from_mrp(s1) @ mrp.dcm_from_mrp(s2).T,
                       atol=1e-9)


@SET
@given(vec)
def test_prv_and_quat_roundtrip(s):
    s = mrp.mrp_switch(s)
    assert np.allclose(mrp.mrp_from_prv(mrp.prv_from_mrp(s)), s, atol=1e-12)
    q = mrp.quat_from_mrp(s)
    assert np.isclose(np.linalg.norm(q), 1.0)
    assert np.allclose(mrp.mrp_from_quat(q), s, atol=1e-12)
    rv = Rotation.from_quat([q[1], q[2], q[3], q[0]]).as_rotvec()
    assert np.allclose(mrp.prv_from_mrp(s), rv, atol=1e-10)


@SET
@given(vec, vec)
def test_bmatrix_kinematics_vs_finite_difference(s, w):
    """C' = -[w x] C for omega_BN in B; sigma' = B w / 4 must reproduce it."""
    s = mrp.mrp_switch(s)
    sdot = mrp.mrp_rate(s, w)
    h = 1e-6
    cdot = (mrp.dcm_from_mrp(s + h * sdot) - mrp.dcm_from_mrp(s - h * sdot)) / (2 * h)
    expect = -mrp.skew(w) @ mrp.dcm_from_mrp(s)
    assert np.allclose(cdot, expect, atol=1e-7 * (1 + np.linalg.norm(w)))


def test_bmatrix_identity():
    # S&J eq. 3.162: B^T B = (1 + s^2)^2 I
    rng = np.random.default_rng(1)
    for _ in range(20):
        s = rng.uniform(-1, 1, 3)
        b = mrp.mrp_bmat(s)
        assert np.allclose(b.T @ b, (1 + s @ s) ** 2 * np.eye(3))


@pytest.mark.parametrize("i", range(3))
def test_near_360_composition(i):
    # two 179.9 deg rotations about the same axis: sum near 360 deg, the singular branch
    e = np.zeros(3)
    e[i] = 1.0
    s = mrp.mrp_from_prv(np.radians(179.9) * e)
    out = mrp.mrp_add(s, s)
    assert np.all(np.isfinite(out)) and np.linalg.norm(out) <= 1.0
    assert np.allclose(mrp.dcm_from_mrp(out), mrp.dcm_from_mrp(s) @ mrp.dcm_from_mrp(s), atol=1e-9)


def test_scalar_forms_against_dcm_algebra():
    """Outside truth: S&J eqs. 3.160/3.161 in DCM form, [FN] = [FB][BN] and
    [BR] = [BN][RN]^T, and C v for the rotation; results are short sets."""
    rng = np.random.default_rng(0)
    for _ in range(300):
        a = rng.uniform(-1.5, 1.5, 3)
        b = rng.uniform(-1.5, 1.5, 3)
        v = rng.normal(size=3)
        ca, cb = mrp.dcm_from_mrp(a), mrp.dcm_from_mrp(b)
        s = np.array(mrp.mrp_add_s(*a, *b))
        assert s @ s <= 1.0 + 1e-15
        np.testing.assert_allclose(mrp.dcm_from_mrp(s), cb @ ca, atol=1e-13)
        d = np.array(mrp.mrp_sub_s(*a, *b))
        assert d @ d <= 1.0 + 1e-15
        np.testing.assert_allclose(mrp.dcm_from_mrp(d), ca @ cb.T, atol=1e-13)
        np.testing.assert_allclose(mrp.mrp_rotate_s(*a, *v), ca @ v, atol=1e-13)
        np.testing.assert_array_equal(mrp.mrp_add(a, b), s)
