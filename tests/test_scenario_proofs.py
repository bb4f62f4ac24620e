"""The proofs behind the fast scenario rows, against brute force on adversarial flights.

:mod:`ideas_hpc.core.mapping.scenario_proofs` claims, from the nominal flight
alone, what every flight within a deviation budget sees (a witness image and
its proof) and where it cannot see (windows). Real scenarios stay well inside
the budget, so here the flights are built to sit on its edge: every image's
camera is moved by 0.9-1.0 of the position budget and rotated by 0.9-1.0 of
the DCM budget, in random directions, and the first images fly arbitrary
attitudes (a converging controller). The oracle is the flyby pipeline's own
rows of those flights (:func:`ideas_hpc.design.candidates.rows_from_views`) and
a brute-force sweep of every image.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from numba import njit

from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.core.mapping.coverage import first_image_by_spacecraft
from ideas_hpc.core.mapping.records import Camera, Nominal
from ideas_hpc.core.mapping.scenario_proofs import BC_ANY, S_MAX
from ideas_hpc.core.mapping.scenario_rows import _proven
from ideas_hpc.core.mapping.visibility import _seen
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.montecarlo.scenario_rows import RowEngine
from ideas_hpc.montecarlo.scenarios import grid_theta, nominal_start

ROOT = Path(__file__).resolve().parent.parent
DESIGN = ROOT / "campaigns" / "eros-design-nominal.toml"


def _rotations(rng, n, angle):
    """(n, 3, 3) rotations by ``angle`` (rad, per matrix) about random axes."""
    a = rng.normal(size=(n, 3))
    a /= np.linalg.norm(a, axis=1)[:, None]
    K = np.zeros((n, 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -a[:, 2], a[:, 1], -a[:, 0]
    K -= K.transpose(0, 2, 1)
    s, c = np.sin(angle)[:, None, None], np.cos(angle)[:, None, None]
    return np.eye(3) + s * K + (1.0 - c) * K @ K


def _edge_flight(rng, r_nom, dcm_nom, bc, br, n_wild=0):
    """The nominal flight moved to the edge of the budget ``(bc, br)``; the first
    ``n_wild`` images of each candidate in arbitrary attitudes."""
    K, n, _ = r_nom.shape
    u = rng.normal(size=(K, n, 3))
    u /= np.linalg.norm(u, axis=2)[..., None]
    r = r_nom + br * rng.uniform(0.9, 1.0, size=(K, n, 1)) * u
    # ||R - I||_F = 2 sqrt(2) sin(theta / 2)
    theta = 2.0 * np.arcsin(bc * rng.uniform(0.9, 1.0, size=K * n) / (2.0 * np.sqrt(2.0)))
    if n_wild:
        theta.reshape(K, n)[:, :n_wild] = rng.uniform(0.0, np.pi, size=(K, n_wild))
    dcm = (_rotations(rng, K * n, theta).reshape(K, n, 3, 3) @ dcm_nom)
    return np.ascontiguousarray(r), np.ascontiguousarray(dcm)


@pytest.fixture(scope="module")
def engine(eros1708):
    c = load(DESIGN, [])
    setup = setup_from_campaign(c)
    theta = grid_theta(np.deg2rad(12.0))
    r0, v0 = nominal_start(setup, theta)
    eng = RowEngine(setup, theta, r0, v0)
    eng.budget = (0.02, 400.0)
    return eng.prepare(None)


def test_witness_proofs_hold_on_the_budget_edge(engine):
    # Flights on the edge of the budget: the fast rows (which settle most seen
    # vertices by their witness proof, without a test) equal the pipeline's.
    rng = np.random.default_rng(7)
    r_nom, dcm_nom = engine.nominal()
    bc, br = engine.budget
    settled = 0
    for n_wild in (0, 0, 40):
        r, dcm = _edge_flight(rng, r_nom, dcm_nom, bc, br, n_wild)
        fast = engine.rows(r, dcm)
        full = engine._full(r, dcm)
        np.testing.assert_array_equal(fast, full)
        assert full.any() and not full.all()
        settled += int(((engine.radius > 0) & full).sum())
    assert settled > 0.5 * full.sum()          # the proofs were exercised


def test_windows_hold_on_the_budget_edge(engine):
    # No image outside a (candidate, vertex)'s window sees it in a flight within
    # the budget: the first and last seeing images, by brute force over every image.
    rng = np.random.default_rng(8)
    r_nom, dcm_nom = engine.nominal()
    bc, br = engine.budget
    mesh, cam0, opts, bvh = engine._static()
    win = engine.window.astype(np.int64)
    any_first = engine.unseen_any.astype(np.int64)
    assert BC_ANY > 2.0 * np.sqrt(2.0)         # beyond any two rotations' distance
    inside = 0
    for n_wild in (0, 40):
        r, dcm = _edge_flight(rng, r_nom, dcm_nom, bc, br, n_wild)
        cam = cam0._replace(r_T_m=r, dcm_BT=dcm)
        first = first_image_by_spacecraft(mesh, cam, opts, bvh)
        back = cam._replace(r_T_m=np.ascontiguousarray(r[:, ::-1]),
                            dcm_BT=np.ascontiguousarray(dcm[:, ::-1]))
        last = first_image_by_spacecraft(mesh, back, opts, bvh)
        last = np.where(last >= 0, r.shape[1] - 1 - last, -1)
        seen = first >= 0
        # any attitude: nothing is seen before the any-attitude window opens
        assert np.all(any_first[seen] >= 0) and np.all(first[seen] >= any_first[seen])
        if n_wild == 0:
            assert np.all(win[seen, 0] >= 0)
            assert np.all(first[seen] >= win[seen, 0]) and np.all(last[seen] <= win[seen, 1])
        else:
            tame = seen & (last >= n_wild)
            assert np.all(last[tame] <= win[tame, 1])
        inside += int(seen.sum())
    assert inside > 0


def _turn(dcm, q, angle, away):
    """``dcm`` turned by ``angle`` (rad) so that camera-frame ``q`` moves away from
    (``away``) or toward the boresight +z, in its plane."""
    z = np.array([0.0, 0.0, 1.0])
    a = np.cross(z, q)
    n = np.linalg.norm(a)
    a = a / n if n > 0 else np.array([1.0, 0.0, 0.0])
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    best = None
    for sgn in (1.0, -1.0):
        R = np.eye(3) + np.sin(sgn * angle) * K + (1.0 - np.cos(sgn * angle)) * K @ K
        tilt = np.arccos(np.clip((R @ q)[2] / np.linalg.norm(q), -1.0, 1.0))
        if best is None or (tilt > best[0]) == away:
            best = (tilt, R)
    return best[1] @ dcm


def _unit_off(rng, axis):
    """A random unit vector perpendicular to ``axis``."""
    u = np.cross(axis, rng.normal(size=3))
    return u / np.linalg.norm(u)


@njit
def _one_image(r, dcm, cam0):
    return Camera(r.reshape(1, 1, 3), dcm.reshape(1, 1, 3, 3), cam0.times_s[:1], cam0.tan_eta,
                  cam0.near_m, cam0.far_m, cam0.exact)


@njit
def _witness_probe(j, r, dcm, r_w, dcm_w, slack, radius, mesh, cam0, opts, bvh):
    """(claimed by the proof, seen) for one camera at a witness image."""
    cam = _one_image(r, dcm, cam0)
    z = np.zeros((1, 1), dtype=np.int64)
    sl = np.full((1, mesh.vertices_T_m.shape[0]), slack)
    rad = np.full((1, mesh.vertices_T_m.shape[0]), radius)
    nominal = Nominal(z, sl, rad, np.zeros((1, 1, 2), dtype=np.int64), z, z[0], z[0],
                      r_w.reshape(1, 1, 3), dcm_w.reshape(1, 1, 3, 3), np.zeros(3))
    return (_proven(nominal, mesh.vertices_T_m, j, cam, 0, 0),
            _seen(j, 0, 0, mesh, cam, opts, bvh, opts.occlusion, opts.illumination))


@njit
def _seen_one(j, r, dcm, mesh, cam0, opts, bvh):
    return _seen(j, 0, 0, mesh, _one_image(r, dcm, cam0), opts, bvh, opts.occlusion,
                 opts.illumination)


def test_witness_proofs_against_their_worst_cameras(engine):
    # For witnessed (candidate, vertex) pairs: cameras moved by up to 1.3x the
    # proof radius (along -n, which erodes culling and elevation, or across the
    # sight line, which probes the clear cone) and turned by up to 2x the DCM
    # deviation the proof allows toward the nearest edge of the field of view.
    # Whenever the proof claims the camera sees the vertex, the exact test agrees;
    # and the probes do reach cameras that do not see it (the proof has work to do).
    rng = np.random.default_rng(11)
    r_nom, dcm_nom = engine.nominal()
    mesh, cam0, opts, bvh = engine._static()
    assert not opts.illumination                   # the probes use image 0's Sun
    ks, js = np.nonzero(engine.witness >= 0)
    pick = rng.choice(ks.size, 3000, replace=False)
    claimed = unseen = 0
    for k, j in zip(ks[pick], js[pick]):
        w = int(engine.witness[k, j])
        slack, radius = float(engine.slack_q[k, j]), float(engine.radius[k, j])
        p, n = mesh.vertices_T_m[j], mesh.normals_T[j]
        r_w, C_w = r_nom[k, w], dcm_nom[k, w]
        los = (r_w - p) / np.linalg.norm(r_w - p)
        d = max(radius, 1.0) * rng.uniform(0.0, 1.3)
        step = -n / np.linalg.norm(n) if rng.random() < 0.5 else _unit_off(rng, los)
        r = r_w + d * step
        dist = np.linalg.norm(p - r)
        c_max = max(0.0, (slack - S_MAX * d) / (dist + d))
        c = c_max * rng.uniform(0.3, 2.0)
        angle = 2.0 * np.arcsin(min(1.0, c / (2.0 * np.sqrt(2.0))))   # ||R - I||_F = c
        dcm = _turn(C_w, C_w @ (p - r), angle, away=True)
        proven, seen = _witness_probe(j, r, np.ascontiguousarray(dcm), r_w,
                                      np.ascontiguousarray(C_w), slack, radius, mesh, cam0,
                                      opts, bvh)
        assert seen or not proven, (k, j, w, d, c, radius, slack)
        claimed += proven
        unseen += not seen
    assert claimed > 500 and unseen > 100


def test_windows_against_their_best_cameras(engine):
    # Just outside a (candidate, vertex)'s budget window, the camera that tries
    # hardest within the budget (boresight turned toward the vertex by the full
    # DCM budget, position moved by the full position budget along the normal,
    # toward the vertex or across the sight line) still does not see it; before
    # the any-attitude window, not even a camera pointed straight at it does.
    rng = np.random.default_rng(12)
    r_nom, dcm_nom = engine.nominal()
    mesh, cam0, opts, bvh = engine._static()
    bc, br = engine.budget
    n_img = r_nom.shape[1]
    angle = 2.0 * np.arcsin(bc / (2.0 * np.sqrt(2.0)))
    win = engine.window.astype(np.int64)
    cells = []
    for side in (0, 1):
        ks, js = np.nonzero((win[..., side] >= 0) & (win[..., 1 - side] >= 0))
        i = win[ks, js, side] + (-1 if side == 0 else 1)
        ok = (i >= 0) & (i < n_img)
        cells += list(zip(ks[ok], js[ok], i[ok], [False] * int(ok.sum())))
    a = engine.unseen_any.astype(np.int64)
    ks, js = np.nonzero(a > 0)
    cells += list(zip(ks, js, a[ks, js] - 1, [True] * ks.size))
    pick = rng.choice(len(cells), min(4000, len(cells)), replace=False)
    probed = [0, 0]
    for t in pick:
        k, j, i, any_attitude = cells[t]
        p, n = mesh.vertices_T_m[j], mesh.normals_T[j]
        r_i, C_i = r_nom[k, i], dcm_nom[k, i]
        los = (r_i - p) / np.linalg.norm(r_i - p)
        choice = rng.integers(3)
        step = (n / np.linalg.norm(n), -los, _unit_off(rng, los))[choice]
        r = r_i + br * rng.uniform(0.99, 1.0) * step
        q = C_i @ (p - r)
        turn = np.pi if any_attitude else angle
        tilt = np.arccos(np.clip(q[2] / np.linalg.norm(q), -1.0, 1.0))
        dcm = _turn(C_i, q, min(turn, tilt), away=False)
        assert not _seen_one(j, r, np.ascontiguousarray(dcm), mesh, cam0, opts, bvh), \
            (k, j, i, any_attitude, choice)
        probed[any_attitude] += 1
    assert min(probed) > 100
