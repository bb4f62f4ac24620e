"""Exact per-candidate rows of a perturbed flight, re-testing only what can change (issue 20).

A scenario moves every candidate's camera by a small deviation from its
nominal flight. With a *budget* ``(B_C, B_r)`` (DCM and position deviation)
fixed before any scenario, :mod:`ideas_hpc.core.mapping.scenario_proofs` proves
once, on the nominal flight, what every flight within the budget sees or
cannot see: per (candidate, vertex) a witness image with its proof, and a
window of images outside which no camera within the budget sees the vertex
(and a wider one for any attitude). :func:`perturbed_rows` then decides each
(candidate, vertex) of a scenario exactly. Let ``i_ok`` be the first image
from which the candidate's deviation stays within the budget (e.g. after the
closed-loop attitude has converged) and ``i_pos`` the same for the position
deviation alone (:func:`deviation_start`).

* a nominally seen vertex whose witness proof holds for the flown camera's
  deviation at the witness image (position and DCM) is seen without a test;
  otherwise it is tested exactly at its witness image (a hit settles it);
* anything not settled is scanned exactly
  (:func:`~ideas_hpc.core.mapping.visibility._seen_hint` over the perturbed
  flight's time tree): every image before ``min(i_pos, i_ok)``, the images of
  ``[i_pos, i_ok)`` in its any-attitude window, and those from ``i_ok`` on in
  its budget window.

Every answer is either an exact test on the perturbed flight or a proof from
the bounds, so rows equal a full recomputation bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.mapping.coverage import _is_strict
from ideas_hpc.core.mapping.records import TimeTree
from ideas_hpc.core.mapping.scenario_proofs import S_MAX
from ideas_hpc.core.mapping.segments import FRAME, cone_in_frame, face_cone_frame
from ideas_hpc.core.mapping.time_tree import (LEAF, _below_elevation, _classify, dcm_gap2,
                                              fill_tree, gap, gram_error2, scan_tree_unfilled)
from ideas_hpc.core.mapping.visibility import _seen, _seen_hint


@njit(cache=True, inline="always")
def _deviation(r_nom, dcm_nom, r_T, dcm_BT, k, bc, br):
    """:func:`deviation_start` for candidate ``k``: ``(i_ok, i_pos, worst)``, ``worst``
    the largest ``||C C^T - I||_F^2`` (inf: a reflection, or a DCM or position that
    is not finite)."""
    i_ok = 0
    i_pos = 0
    worst = 0.0
    for i in range(r_T.shape[1] - 1, -1, -1):
        dc = dcm_gap2(dcm_BT, k, i, dcm_nom, i)
        g = gram_error2(dcm_BT, k, i)
        det = (dcm_BT[k, i, 0, 0] * (dcm_BT[k, i, 1, 1] * dcm_BT[k, i, 2, 2]
                                     - dcm_BT[k, i, 1, 2] * dcm_BT[k, i, 2, 1])
               - dcm_BT[k, i, 0, 1] * (dcm_BT[k, i, 1, 0] * dcm_BT[k, i, 2, 2]
                                       - dcm_BT[k, i, 1, 2] * dcm_BT[k, i, 2, 0])
               + dcm_BT[k, i, 0, 2] * (dcm_BT[k, i, 1, 0] * dcm_BT[k, i, 2, 1]
                                       - dcm_BT[k, i, 1, 1] * dcm_BT[k, i, 2, 0]))
        if not det > 0.0:
            g = np.inf                   # a reflection (or NaN): not a rotation
        if not g <= worst:
            worst = g                    # NaN sticks
        dr = gap(r_T, k, i, r_nom, i)
        if not dr < np.inf:
            worst = np.inf               # a position that is not finite: sticks as well
        if i_ok == 0 and not (np.sqrt(dc) <= bc and dr <= br):
            i_ok = i + 1
        if i_pos == 0 and not dr <= br:
            i_pos = i + 1
    return i_ok, i_pos, worst


@njit(cache=True, parallel=True)
def deviation_start(r_nom, dcm_nom, r_T, dcm_BT, bc, br):
    """How far a flight ``(r_T, dcm_BT)`` strays from the nominal ``(r_nom, dcm_nom)``.

    Returns (N,) int64 ``i_ok``, the first image from which every image's deviation
    is within the budget ``(bc, br)`` (``n_img`` when the last image is already
    outside); (N,) int64 ``i_pos``, the same for the position deviation alone; and
    the largest ``||C C^T - I||_F`` of the flown DCMs, which bounds ``||C||_2 <=
    sqrt(1 + it)`` for the proofs (inf when one is a reflection or not finite, or a
    position is not). :func:`perturbed_rows` does the same per candidate itself.
    """
    nsc = r_T.shape[0]
    out = np.empty(nsc, dtype=np.int64)
    out_pos = np.empty(nsc, dtype=np.int64)
    ortho = np.zeros(nsc)
    for k in prange(nsc):
        out[k], out_pos[k], worst = _deviation(r_nom, dcm_nom, r_T, dcm_BT, k, bc, br)
        ortho[k] = np.sqrt(worst)
    return out, out_pos, ortho.max() if nsc > 0 else 0.0


@njit(cache=True, inline="always")
def _scan_range(j, k, a, b, tree, stack, hint, frame, mesh, cam, opts, bvh):
    """Does spacecraft ``k`` see vertex ``j`` in an image ``a <= i < b``? Exact.

    Walks the perturbed flight's time tree: a node failing culling or clipping
    with margin is skipped (:func:`~ideas_hpc.core.mapping.time_tree._classify`), and so
    is a node whose sight lines all lie in a cone the last blocking face
    ``hint[0]`` covers (:func:`~ideas_hpc.core.mapping.segments.face_blocks_cone`); leaf
    images are tested one by one (:func:`~ideas_hpc.core.mapping.visibility._seen_hint`).
    """
    NF = tree.NF
    NI = tree.NI
    strict = _is_strict(opts)
    vertices = mesh.vertices_T_m
    normals = mesh.normals_T
    sin_min_elev = opts.sin_min_elev
    max_range = opts.max_range_m
    occlusion = opts.occlusion
    tri = bvh.tri_m
    tri_vid = bvh.tri_vid
    px = vertices[j, 0]
    py = vertices[j, 1]
    pz = vertices[j, 2]
    nx = normals[j, 0]
    ny = normals[j, 1]
    nz = normals[j, 2]
    nabs = np.sqrt(nx * nx + ny * ny + nz * nz)
    sp = 1
    stack[0] = NI.shape[0] - 1
    while sp > 0:
        sp -= 1
        node = stack[sp]
        i0 = NI[node, 0]
        i1 = NI[node, 1]
        if i1 <= a or i0 >= b:
            continue
        cls = _classify(tree, k, node, px, py, pz, nx, ny, nz, nabs, cam)
        if cls == 0:
            continue
        if cls == 2 and not strict and i0 >= a and i1 <= b:
            return True
        if sin_min_elev > -1.0 or max_range < np.inf:
            if _below_elevation(NF, k, node, px, py, pz, nx, ny, nz, nabs, sin_min_elev,
                                max_range):
                continue
        if occlusion and hint[0] >= 0:
            if hint[1] != hint[0]:      # the face's frame from p, once per blocking face
                hint[1] = hint[0]
                hint[2] = face_cone_frame(tri, tri_vid, hint[0], j, px, py, pz, frame)
            vx = NF[k, node, 9] - px
            vy = NF[k, node, 10] - py
            vz = NF[k, node, 11] - pz
            dist = np.sqrt(vx * vx + vy * vy + vz * vz)
            er = NF[k, node, 14]
            # the cone's half-angle asin(er / dist) < pi/6: its sine er / dist, inflated as
            # face_blocks_cone does (sin(a (1 + 1e-9) + 1e-9) <= sin a + 2e-9 for a <= pi/6)
            if hint[2] and er < 0.5 * dist and cone_in_frame(frame, vx / dist, vy / dist,
                                                             vz / dist, er / dist + 2e-9,
                                                             dist - er):
                continue
        if NI[node, 2] >= 0:
            if NI[node, 3] >= 0:
                stack[sp] = NI[node, 3]
                sp += 1
            stack[sp] = NI[node, 2]
            sp += 1
            continue
        for i in range(max(i0, a), min(i1, b)):
            seen, hint[0] = _seen_hint(j, k, i, hint[0], mesh, cam, opts, bvh)
            if seen:
                return True
    return False


@njit(cache=True, inline="always")
def _proven(nominal, vertices, j, cam, k, w):
    """The witness proof of :func:`~ideas_hpc.core.mapping.scenario_proofs.witness_proofs`
    holds for the flown camera ``cam`` of candidate ``k`` at its witness image ``w``."""
    r_T = cam.r_T_m
    d = gap(r_T, k, w, nominal.r_nom_T_m, w)
    if not d < nominal.radius_m[k, j]:
        return False
    c = dcm_gap2(cam.dcm_BT, k, w, nominal.dcm_nom_BT, w)
    dx = vertices[j, 0] - r_T[k, w, 0]
    dy = vertices[j, 1] - r_T[k, w, 1]
    dz = vertices[j, 2] - r_T[k, w, 2]
    dist = np.sqrt(dx * dx + dy * dy + dz * dz)
    return (np.sqrt(c) * (dist + d) * (1.0 + 1e-12) + S_MAX * d) * (1.0 + 1e-12) \
        < nominal.slack_q_m[k, j]


@njit(cache=True, parallel=True)
def perturbed_rows(nominal, mesh, cam, opts, bvh):
    """(N, V) bool rows of the perturbed flight ``cam`` (module docstring).

    ``nominal`` is a :class:`~ideas_hpc.core.mapping.records.Nominal`: ``witness``,
    ``slack_q_m`` and ``radius_m`` (N, V) from
    :func:`~ideas_hpc.core.mapping.scenario_proofs.witness_proofs`, ``window``
    (N, V, 2) and ``unseen_any`` (N, V) from
    :func:`~ideas_hpc.core.mapping.scenario_proofs.windows` with the budget and
    with any attitude, the nominal flight and the ``budget`` ``(B_C, B_r, tolerance
    on ||C C^T - I||_F)``; other arguments as
    :func:`ideas_hpc.core.mapping.coverage.observed_by_spacecraft`, for the
    perturbed flight. ``i_ok`` and ``i_pos`` (N,) are written here, per candidate
    as :func:`deviation_start`; ``i_ok[k] = -1`` marks a candidate whose flown DCMs
    are not rotations within the tolerance or whose flight is not finite: its row
    is not computed, and the caller must recompute the rows in full. A (candidate,
    vertex) not settled by its witness is scanned exactly (:func:`_scan_range`).
    """
    nv = mesh.vertices_T_m.shape[0]
    nsc = cam.r_T_m.shape[0]
    tree = TimeTree(*scan_tree_unfilled(cam))
    mask = np.zeros((nsc, nv), dtype=np.bool_)
    # candidate-major: one candidate's flight, time tree and rows stay in cache,
    # the tree built right before it is walked
    for k in prange(nsc):
        _candidate_row(np.int64(k), nominal, mesh, cam, opts, bvh, tree, mask[k])
    return mask


@njit(cache=True)
def _candidate_row(k, nominal, mesh, cam, opts, bvh, tree, row):
    """Candidate ``k``'s row (V,) of :func:`perturbed_rows`, written to ``row``, with its
    ``i_ok[k]`` and ``i_pos[k]``; it fills the candidate's nodes of ``tree`` first.

    The kernel's ``prange`` body, compiled on its own: Numba types a ``prange`` body
    twice (in the kernel and in its gufunc) and copy-propagates the inlined scans each
    time, so inside the loop the kernel cost 54 CPU s to compile (the same work).
    """
    witness = nominal.witness
    window = nominal.window
    unseen_any = nominal.unseen_any
    i_ok = nominal.i_ok
    i_pos = nominal.i_pos
    bc, br, ortho_tol = nominal.budget[0], nominal.budget[1], nominal.budget[2]
    vertices = mesh.vertices_T_m
    nv = mesh.vertices_T_m.shape[0]
    # how far this candidate strays, while its flight comes into cache for the
    # tree and the scans (a separate pass over every flight cost more)
    i_ok[k], i_pos[k], worst = _deviation(nominal.r_nom_T_m, nominal.dcm_nom_BT,
                                          cam.r_T_m, cam.dcm_BT, k, bc, br)
    if not np.sqrt(worst) <= ortho_tol:
        i_ok[k] = -1        # not near-rotations (or not finite): no proof holds
        return
    # the tree's S from the gram errors just checked, not computed again
    fill_tree(tree.NF, tree.NI, cam.r_T_m, cam.dcm_BT, k, LEAF, worst)
    stack = np.empty(128, dtype=np.int64)
    hint = np.full(3, -1, dtype=np.int64)
    frame = np.empty(FRAME)
    for j in range(nv):
        w = witness[k, j]
        if w >= 0 and (_proven(nominal, vertices, j, cam, k, w)
                       or _seen(j, k, w, mesh, cam, opts, bvh, opts.occlusion,
                                opts.illumination)):
            row[j] = True
            continue
        hint[0] = -1
        hint[1] = -1        # a new vertex: no face frame yet
        seen = False
        # three ranges of images, scanned in turn through one call site (the inlined
        # scan compiled once: three copies cost about 120 s of compile); an empty
        # range is skipped, which is what the scan answers for it (no image in it)
        for part in range(3):
            if part == 0:
                # before i_ok: every image until i_pos ...
                a, b = 0, min(i_pos[k], i_ok[k])
            elif unseen_any[k, j] < 0:
                break       # no camera of any attitude within the budget sees it
            elif part == 1:
                # ... then from what positions allow
                a, b = max(i_pos[k], unseen_any[k, j]), i_ok[k]
            elif window[k, j, 0] >= 0:
                # from i_ok: in both windows (either proof holds there)
                a = max(window[k, j, 0], i_ok[k], unseen_any[k, j])
                b = window[k, j, 1] + 1
            else:
                break
            if a < b:
                seen = _scan_range(j, k, a, b, tree, stack, hint, frame, mesh, cam, opts, bvh)
                if seen:
                    break
        row[j] = seen
