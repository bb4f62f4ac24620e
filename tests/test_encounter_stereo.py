"""Stereo on an encounter (issue 24): ballistic tracks and ring frames from v_inf.

Two spacecraft pass a sphere on straight lines (gravity off, no spin) at
10 km/s, with the camera on the body centre (``track``). The stereo results of
the quality pass (the swarm's ``stereo``, each spacecraft's own-track stereo,
the spacecraft-pair table) are checked against a brute-force NumPy oracle:
every observation of a vertex from the flown positions, every pair of them,
the convergence angle from ``arccos`` of the unit lines of sight.

On a convex mesh with the whole body inside the field of view and no
elevation limit, a vertex is seen from ``p`` when ``n . (p - r) > 0`` (vertex
normal ``n``), except within a few degrees of its horizon, where vertex and
face normals disagree. The oracle brackets the answer: ``lo`` counts an
observation within 5 deg of the horizon as not seen, ``hi`` as seen. The
kernel's answer must lie between them everywhere, and equal them where they
agree (most vertices).
"""

from __future__ import annotations

import dataclasses
import math
from itertools import combinations

import numpy as np
import pytest

from ideas_hpc.flyby.flight import fly
from ideas_hpc.mapping.coverage import quality_per_spacecraft, stereo_pair_table
from test_encounter import _setup

S_MIN, S_MAX = math.radians(50.0), math.radians(60.0)
MARGIN = math.sin(math.radians(5.0))


@pytest.fixture(scope="module")
def encounter(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("stereo")
    s = _setup(tmp, "speed_km_s = 10.0\napproach_dec_deg = 30.0\napproach_ra_deg = 40.0\n"
               "d_sep_km = 31.2\nbefore_km = 20.0\nafter_km = 20.0", res=4, mu=0.0,
               spin_period=1e15)
    opts = dataclasses.replace(s.coverage, quality=True, require_stereo=True,
                               stereo_min_rad=S_MIN, stereo_max_rad=S_MAX)
    # geometry only: no usable-image test (tracking this close at 10 km/s, the footprint
    # centre's parallax smears some images past a pixel, which the oracle does not model;
    # tests/test_smear.py checks that)
    s = s.with_(eta_rad=math.radians(80.0), near_m=1.0, far_m=1e9, maneuver="track",
                coverage=opts, imaging=None)
    return s, fly(s, [0.0, 1.0])


def _oracle(s, out):
    """Seen (K, I, V) counting near-horizon sightings out (lo) and in (hi); unit lines of
    sight (K, I, V, 3)."""
    r = s.body.shape.vertices_T
    n = s.body.shape.vertex_normals_T / np.linalg.norm(s.body.shape.vertex_normals_T, axis=1,
                                                       keepdims=True)
    los = out.r_img_T[:, :, None, :] - r[None, None]          # vertex -> spacecraft
    u = los / np.linalg.norm(los, axis=-1, keepdims=True)
    cos_e = np.einsum("kivx,vx->kiv", u, n)
    return cos_e > MARGIN, cos_e > 0.0, u


def _stereo(u_a, u_b, seen_a, seen_b, same):
    """Any pair (x seen by a, y seen by b, x != y) with S_MIN <= angle <= S_MAX, per vertex."""
    ang = np.arccos(np.clip(np.einsum("ivx,jvx->ijv", u_a, u_b), -1, 1))
    ok = (ang >= S_MIN) & (ang <= S_MAX) & seen_a[:, None, :] & seen_b[None, :, :]
    if same:
        ok &= ~np.eye(ok.shape[0], dtype=bool)[:, :, None]
    return ok.any(axis=(0, 1))


def _check(got, lo, hi, what):
    """got within [lo, hi]; lo == hi on most vertices, with both answers among them."""
    assert not (lo & ~hi).any()
    assert not (lo & ~got).any() and not (got & ~hi).any(), what
    sure = lo == hi
    assert sure.mean() > 0.8, what
    assert 0.05 < lo[sure].mean() < 0.95, what  # a comparison that can fail both ways


def test_the_tracks_are_straight_and_the_camera_sees_the_whole_disc(encounter):
    s, out = encounter
    d = np.diff(out.r_img_T, axis=1)
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 2e3, rtol=1e-9)  # 10 km/s, 5 Hz
    np.testing.assert_allclose(np.cross(d[:, 1:], d[:, :-1]), 0.0, atol=1e-3)
    # the body's angular radius (asin R/d, d >= 31.2 km) is inside the 80 deg field
    bore = out.dcm_BT[:, :, 2]
    rad = np.linalg.norm(out.r_img_T, axis=-1)
    assert (np.einsum("kix,kix->ki", bore, -out.r_img_T) / rad > math.cos(math.radians(25))).all()


def test_stereo_of_the_swarm_matches_every_pair(encounter):
    s, out = encounter
    lo, hi, u = _oracle(s, out)
    k, i = lo.shape[:2]
    u_all = u.reshape(k * i, -1, 3)
    lo_all, hi_all = lo.reshape(k * i, -1), hi.reshape(k * i, -1)
    _check(out.coverage.quality.stereo, _stereo(u_all, u_all, lo_all, lo_all, True),
           _stereo(u_all, u_all, hi_all, hi_all, True), "swarm")
    observed = out.coverage.observed
    assert not (lo_all.any(axis=0) & ~observed).any()
    assert not (observed & ~hi_all.any(axis=0)).any()


def test_own_track_stereo_and_the_pair_table_match_every_pair(encounter):
    s, out = encounter
    lo, hi, u = _oracle(s, out)
    args = (s.body.shape, out.r_img_T, out.dcm_BT, s.image_times, s.eta_rad, s.near_m, s.far_m)
    sun = s.sun_T(s.image_times)
    own = quality_per_spacecraft(*args, options=s.coverage, sun_T=sun)["stereo"]
    pairs = stereo_pair_table(*args, options=s.coverage, sun_T=sun)
    for k in range(lo.shape[0]):
        _check(own[k], _stereo(u[k], u[k], lo[k], lo[k], True),
               _stereo(u[k], u[k], hi[k], hi[k], True), f"own track {k}")
    for row, (a, b) in enumerate(combinations(range(lo.shape[0]), 2)):
        _check(pairs[row], _stereo(u[a], u[b], lo[a], lo[b], False),
               _stereo(u[a], u[b], hi[a], hi[b], False), f"pair {a} {b}")
