"""Observation-quality pass (issue 14) on eros001708: a NumPy per-image, per-pair
brute force of every variable, shadows against trimesh on 24 viewpoints, and
the cone query that clears runs of images from occlusion."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ideas_hpc.core.mapping import bvh as cbvh
from ideas_hpc.mapping.coverage import compute_coverage
from ideas_hpc.mapping.options import CoverageOptions
from test_coverage import _trimesh_blocked, eros_rays, look_at  # noqa: F401 (fixture)
from test_quality import DEG, _pairwise


# ---------------------------------------------------------------- brute force on eros001708

def quality_oracle(shape, r, C, t, eta, near, far, opts, sun, active=None):
    """NumPy per image (all vertices at once) and per pair (stereo), the issue 14
    definitions as written. Rays are the BVH primitive (checked against trimesh in
    test_coverage.py and below)."""
    p = shape.vertices_T
    n = shape.vertex_normals_T
    V = len(p)
    N, I = r.shape[:2]
    tree = cbvh.build_bvh(p, shape.faces)
    tan = math.tan(eta)
    sin_e = -2.0 if opts.min_elevation_rad is None else math.sin(opts.min_elevation_rad)
    act = np.ones(N, bool) if active is None else active
    lim = opts.limits
    obs = np.zeros((N, I, V), bool)
    for k in range(N):
        if not act[k]:
            continue
        for i in range(I):
            dx, dy, dz = (p[:, a] - r[k, i, a] for a in range(3))
            los_n = (-dx) * n[:, 0] + (-dy) * n[:, 1] + (-dz) * n[:, 2]
            if opts.mode == "exact":
                ok = los_n > 0.0
            else:
                ok = r[k, i, 0] * n[:, 0] + r[k, i, 1] * n[:, 1] + r[k, i, 2] * n[:, 2] >= 0.0
            q = [C[k, i, a, 0] * dx + C[k, i, a, 1] * dy + C[k, i, a, 2] * dz for a in range(3)]
            ok &= (q[2] > 0) & (q[2] >= near) & (q[2] <= far)
            ok &= (np.abs(q[0]) <= tan * q[2]) & (np.abs(q[1]) <= tan * q[2])
            if sin_e > -1.0:
                rng = np.sqrt(dx * dx + dy * dy + dz * dz)
                ok &= los_n >= rng * sin_e
            if opts.occlusion:
                for j in np.flatnonzero(ok):
                    if cbvh.segment_blocked(*tree, p[j, 0], p[j, 1], p[j, 2], -dx[j], -dy[j],
                                            -dz[j], 1.0, j):
                        ok[j] = False
            obs[k, i] = ok
    lit_ij = {}

    def lit_at(i, j):
        if (i, j) not in lit_ij:
            s = sun[i]
            lit_ij[i, j] = bool(s[0] * n[j, 0] + s[1] * n[j, 1] + s[2] * n[j, 2] > 0.0) and \
                not cbvh.segment_blocked(*tree, p[j, 0], p[j, 1], p[j, 2], s[0], s[1], s[2],
                                         np.inf, j)
        return lit_ij[i, j]

    def angle(a, b):
        c = np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1], a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                      a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], 1)
        return np.arctan2(np.sqrt(c[:, 0] * c[:, 0] + c[:, 1] * c[:, 1] + c[:, 2] * c[:, 2]),
                          a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2])

    out = {name: np.zeros(V, bool) for name in ("lit", "stereo", "mapped")}
    out.update({name: np.full(V, np.nan) for name in
                ("best_resolution", "emission_at_best", "incidence_at_best", "phase_at_best",
                 "first_seen")})
    out["times_seen"] = np.zeros(V, np.int32)
    out["n_spacecraft_seen"] = np.zeros(V, np.int32)
    for j in range(V):
        ks, iis = np.nonzero(obs[:, :, j])             # (k, i) order
        lits = np.array([lit_at(i, j) for i in iis], bool)
        if opts.illumination:
            ks, iis, lits = ks[lits], iis[lits], lits[lits]
        if len(ks) == 0:
            continue
        out["times_seen"][j] = len(ks)
        out["first_seen"][j] = t[iis].min()
        out["n_spacecraft_seen"][j] = len(set(ks))
        out["lit"][j] = lits.any()
        L = r[ks, iis] - p[j]
        nn = np.broadcast_to(n[j], L.shape)
        S = sun[iis]
        ln = L[:, 0] * n[j, 0] + L[:, 1] * n[j, 1] + L[:, 2] * n[j, 2]
        rng2 = L[:, 0] * L[:, 0] + L[:, 1] * L[:, 1] + L[:, 2] * L[:, 2]
        with np.errstate(divide="ignore"):
            res = np.where(ln > 0, opts.rho * rng2 / np.where(ln > 0, ln, 1.0), np.inf)
        e, inc, g = angle(nn, L), angle(nn, S), angle(S, L)
        b = int(np.argmin(res))
        out["best_resolution"][j] = res[b]
        out["emission_at_best"][j] = e[b]
        out["incidence_at_best"][j] = inc[b]
        out["phase_at_best"][j] = g[b]
        rng = np.sqrt(rng2)
        nabs = math.sqrt(n[j, 0] * n[j, 0] + n[j, 1] * n[j, 1] + n[j, 2] * n[j, 2])
        ce, ci, cg = (math.cos(x) if np.isfinite(x) else -2.0 for x in lim[1:4])
        ns = S[:, 0] * n[j, 0] + S[:, 1] * n[j, 1] + S[:, 2] * n[j, 2]
        sl = S[:, 0] * L[:, 0] + S[:, 1] * L[:, 1] + S[:, 2] * L[:, 2]
        use = (res <= lim[0]) & (ln >= ce * rng * nabs) & (ns >= ci * nabs) & (sl >= cg * rng)
        if opts.require_lit:
            use &= lits
        U = L[use] / rng[use][:, None]
        out["stereo"][j] = len(U) > 1 and _pairwise(U, lim[4], lim[5])
        out["mapped"][j] = use.any() and (out["stereo"][j] or not opts.require_stereo)
    return out


def eros_views(N=5, I=30, seed=3):
    rng = np.random.default_rng(seed)
    r = np.empty((N, I, 3))
    C = np.empty((N, I, 3, 3))
    for k in range(N):
        u0 = rng.normal(size=3)
        u0 /= np.linalg.norm(u0)
        w = np.cross(u0, rng.normal(size=3))
        w /= np.linalg.norm(w)
        sweep = rng.uniform(5, 50) * DEG     # some tracks give stereo on their own
        dist = rng.uniform(40e3, 80e3)
        for i in range(I):
            a = sweep * (i / (I - 1) - 0.5)
            r[k, i] = dist * (math.cos(a) * u0 + math.sin(a) * w)
            C[k, i] = look_at(r[k, i])
    t = np.arange(I) * 2.0
    ph = np.linspace(0, 8 * DEG, I)
    sun = np.c_[np.cos(ph), np.sin(ph), 0.3 * np.ones(I)]
    sun /= np.linalg.norm(sun, axis=1)[:, None]
    return r, C, t, sun


CASES = {
    "exact-occl-all-limits": dict(mode="exact", occlusion=True, require_lit=True,
                                  max_resolution_m=0.6, max_emission_rad=60 * DEG,
                                  max_incidence_rad=75 * DEG, max_phase_rad=110 * DEG,
                                  require_stereo=True),
    "paper-quality-only": dict(quality=True),
    "illum-elev-stereo-detector": dict(mode="exact", occlusion=True, illumination=True,
                                       min_elevation_rad=10 * DEG, require_stereo=True,
                                       stereo_min_rad=5 * DEG, stereo_max_rad=25 * DEG,
                                       pixel_pitch_m=7e-6, focal_length_m=0.5),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_quality_matches_brute_force_on_eros(eros1708, case):
    shape = eros1708.shape
    r, C, t, sun = eros_views()
    opts = CoverageOptions(**CASES[case])
    active = np.array([True, True, False, True, True]) if "illum" in case else None
    eta = 20 * DEG
    res = compute_coverage(shape, r, C, t, eta, 1e-3, 1e6, options=opts, sun_T=sun,
                           active=active)
    ref = quality_oracle(shape, r, C, t, eta, 1e-3, 1e6, opts, sun, active)
    q = res.quality
    for name in ("lit", "stereo", "mapped", "n_spacecraft_seen"):
        np.testing.assert_array_equal(getattr(q, name), ref[name], err_msg=name)
    np.testing.assert_array_equal(res.times_seen, ref["times_seen"])
    np.testing.assert_array_equal(res.first_seen, ref["first_seen"])
    np.testing.assert_array_equal(res.observed, ref["times_seen"] > 0)
    np.testing.assert_allclose(q.best_resolution, ref["best_resolution"], rtol=1e-12)
    for name in ("emission_at_best", "incidence_at_best", "phase_at_best"):
        np.testing.assert_allclose(getattr(q, name), ref[name], rtol=0, atol=1e-12,
                                   err_msg=name)
    # the test exercises every output
    assert 0 < q.stereo.sum() < res.observed.sum(), (q.stereo.sum(), res.observed.sum())
    assert 0 < q.lit.sum() <= res.observed.sum()
    assert q.n_spacecraft_seen.max() >= 2
    if opts.requirement:
        assert 0 < q.mapped.sum() < res.observed.sum()
        assert res.coverage < res.coverage_seen
    # observed, first_seen and counts are those of the coverage kernels
    plain = dataclasses.replace(opts, quality=False, require_lit=False, max_resolution_m=None,
                                max_emission_rad=None, max_incidence_rad=None, max_phase_rad=None,
                                require_stereo=False)
    base = compute_coverage(shape, r, C, t, eta, 1e-3, 1e6, options=plain, sun_T=sun,
                            active=active)
    np.testing.assert_array_equal(base.times_seen, res.times_seen)
    np.testing.assert_array_equal(base.first_seen, res.first_seen)
    assert base.coverage == res.coverage_seen


# ---------------------------------------------------------------- shadows vs trimesh

def test_lit_matches_trimesh_on_24_viewpoints(eros1708, eros_rays):
    shape = eros1708.shape
    mesh, adjacency = eros_rays
    rng = np.random.default_rng(11)
    p, n = shape.vertices_T, shape.vertex_normals_T
    opts = CoverageOptions(mode="exact", quality=True)
    n_shadow = n_lit = 0
    for _ in range(24):
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        r = (u * rng.uniform(25e3, 160e3))[None, None]
        C = look_at(r[0, 0])[None, None]
        s = rng.normal(size=3)
        s /= np.linalg.norm(s)
        res = compute_coverage(shape, r, C, np.zeros(1), 60 * DEG, 1e-4, 1e6, options=opts,
                               sun_T=s[None])
        facing = res.observed & (n @ s > 0)
        idx = np.flatnonzero(facing)
        blocked = _trimesh_blocked(mesh, shape, idx, p[idx] + 1e6 * s, adjacency)
        truth = np.zeros(shape.n_vertices, bool)
        truth[idx[~blocked]] = True
        np.testing.assert_array_equal(res.quality.lit, truth)
        n_shadow += int(blocked.sum())
        n_lit += int(truth.sum())
    assert n_shadow > 50 and n_lit > 1000


def test_cone_clear_is_conservative_on_eros(eros1708):
    """A cleared cone holds no blocked ray (dense samples inside it); blocked axes are
    never cleared; and most well-placed cones do clear."""
    shape = eros1708.shape
    tree = cbvh.build_bvh(shape.vertices_T, shape.faces)
    p, n = shape.vertices_T, shape.vertex_normals_T
    rng = np.random.default_rng(5)
    n_clear = n_tested = 0
    for _ in range(400):
        j = int(rng.integers(len(p)))
        a = n[j] + rng.normal(size=3) * 0.8
        a /= np.linalg.norm(a)
        alpha = 10.0 ** rng.uniform(-4, -1)
        clear = cbvh.cone_clear(*tree, *p[j], *a, alpha, j)
        # rays on the cone's rim and inside it
        e1 = np.cross(a, [0.3, 0.5, 0.8])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(a, e1)
        phi = rng.uniform(0, 2 * np.pi, 64)
        rad = np.r_[np.full(32, alpha), rng.uniform(0, alpha, 32)]
        dirs = (np.cos(rad)[:, None] * a + np.sin(rad)[:, None]
                * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2))
        blocked = [cbvh.segment_blocked(*tree, *p[j], *d, np.inf, j) for d in dirs]
        if clear:
            assert not any(blocked)
            n_clear += 1
        if cbvh.segment_blocked(*tree, *p[j], *a, np.inf, j):
            assert not clear
        n_tested += 1
    assert n_clear > n_tested // 4
