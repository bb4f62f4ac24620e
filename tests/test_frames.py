import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ideas_hpc.core.dynamics.frames import dcm_RS, dcm_RT, dcm_TS, ring_positions_T

angles = st.floats(0.0, 2 * np.pi, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(theta=angles, zc=st.floats(-3e4, 3e4))
def test_ring_frame_axes(theta, zc):
    d = 155.9e3
    r0 = ring_positions_T(np.array([0.0]), d, np.array([zc]))[0]
    centre = np.array([0.0, 0.0, zc])
    ts = dcm_TS(r0, centre, np.array([0.0, 0.0, 100.0]))
    rt = dcm_RT(theta, ts)
    r_i = ring_positions_T(np.array([theta]), d, np.array([zc]))[0]
    x_R, y_R, z_R = rt  # rows are the R axes in T components
    # z toward the ring centre
    to_centre = (centre - r_i) / np.linalg.norm(centre - r_i)
    assert np.allclose(z_R, to_centre, atol=1e-12)
    # x along the swarm z axis (the column z_S of [TS])
    assert np.allclose(x_R, ts[:, 2], atol=1e-12)
    # right-handed orthonormal
    assert np.allclose(rt @ rt.T, np.eye(3), atol=1e-12)
    assert np.isclose(np.linalg.det(rt), 1.0)
    assert np.allclose(np.cross(x_R, y_R), z_R, atol=1e-12)


def test_swarm_frame_of_a_ring_is_T():
    ts = dcm_TS(np.array([1e5, 0, -3e4]), np.array([0, 0, -3e4]), np.array([0, 0, 100.0]))
    assert np.allclose(ts, np.eye(3))


def test_ring_frame_rows_match_spec():
    th = 0.7
    m = dcm_RS(th)
    assert np.allclose(m, [[0, 0, 1], [-np.sin(th), np.cos(th), 0], [-np.cos(th), -np.sin(th), 0]])
