"""A face that blocks a cone of sight lines blocks every line in it (issue 31).

:func:`~ideas_hpc.core.mapping.segments.face_blocks_cone` lets the bank's scans skip
whole runs of images; :func:`~ideas_hpc.core.mapping.scenario_rows._scan_range` uses
it in two parts, the face's frame from the vertex once per blocking face
(:func:`~ideas_hpc.core.mapping.segments.face_cone_frame`) and the cone against it
(:func:`~ideas_hpc.core.mapping.segments.cone_in_frame`), with the cone's sine bounded
without the arcsine. Oracle: the Moller-Trumbore test of each sampled segment.
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.core.mapping.segments import (FRAME, _crosses, cone_in_frame, face_blocks_cone,
                                             face_cone_frame)


def _cone_dirs(a, alpha, rng, n=48):
    """Unit directions on the rim of the cone (axis ``a``, half-angle ``alpha``) and inside."""
    e1 = np.cross(a, [0.3, 0.5, 0.8])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    phi = rng.uniform(0, 2 * np.pi, n)
    rad = np.r_[np.full(n // 2, alpha), rng.uniform(0, alpha, n - n // 2)]
    return (np.cos(rad)[:, None] * a + np.sin(rad)[:, None]
            * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2))


def test_a_blocking_face_crosses_every_segment_of_the_cone():
    rng = np.random.default_rng(8)
    tri_vid = np.array([[0, 1, 2]])
    blocked = 0
    for _ in range(600):
        corners = rng.normal(size=(3, 3)) * 100.0 + rng.normal(size=3) * 400.0
        tri = np.r_[corners[0], corners[1] - corners[0], corners[2] - corners[0]][None]
        p = np.zeros(3)
        # an axis toward a point of the face, a cone up to the face's angular size
        w = rng.dirichlet(np.ones(3))
        a = w @ corners
        a /= np.linalg.norm(a)
        alpha = 10.0 ** rng.uniform(-4.0, -0.7)
        far = np.linalg.norm(corners, axis=1).max()
        length = far * rng.uniform(0.3, 1.5)
        got = face_blocks_cone(tri, tri_vid, 0, -1, *p, *a, alpha, length)
        frame = np.empty(FRAME)
        split = (face_cone_frame(tri, tri_vid, 0, -1, *p, frame)
                 and cone_in_frame(frame, *a, np.sin(alpha * (1 + 1e-9) + 1e-9), length))
        assert got == split
        if not got:
            continue
        blocked += 1
        for d in _cone_dirs(a, alpha, rng):
            # every segment from p of the given length in the cone crosses the face
            assert _crosses(tri, tri_vid, 0, *p, *(d * length), 1e-9 / length, 1.0, -1)
    assert blocked > 100            # the test is not vacuous


def test_a_face_of_the_vertex_or_a_plane_through_it_blocks_nothing():
    tri = np.array([[0.0, 0.0, 100.0, 50.0, 0.0, 0.0, 0.0, 50.0, 0.0]])
    frame = np.empty(FRAME)
    assert face_cone_frame(tri, np.array([[0, 1, 2]]), 0, -1, 10.0, 10.0, 0.0, frame)
    assert not face_cone_frame(tri, np.array([[0, 7, 2]]), 0, 7, 10.0, 10.0, 0.0, frame)
    assert not face_cone_frame(tri, np.array([[0, 1, 2]]), 0, -1, 10.0, 10.0, 100.0, frame)


def test_the_scans_sine_bound_covers_the_inflated_half_angle():
    # _scan_range passes er / dist + 2e-9 for a half-angle asin(er / dist) < pi / 6;
    # face_blocks_cone inflates the angle to a (1 + 1e-9) + 1e-9
    x = np.r_[np.linspace(0.0, 0.5, 20001), 10.0 ** np.linspace(-12, -0.302, 2000)]
    inflated = np.sin(np.arcsin(x) * (1 + 1e-9) + 1e-9)
    assert np.all(x + 2e-9 >= inflated)
