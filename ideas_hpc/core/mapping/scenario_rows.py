"""Exact per-candidate rows of a perturbed flight, re-testing only what can change (issue 20).

A scenario moves every candidate's camera by a small deviation from its
nominal flight: positions ``r'_i = r_i + dr_i`` and camera DCMs
``C'_i = C_i + dC_i`` at the images. For a vertex ``p``, the camera
coordinates move by (same derivation as :mod:`ideas_hpc.core.mapping.time_tree`)

    q'_i - q_i = (C'_i - C_i)(p - r_i) + C'_i (r_i - r'_i),
    |q'_i - q_i| <= B_C |p - r_i| + s' B_r,

with ``B_C >= ||C'_i - C_i||_F``, ``B_r >= |r'_i - r_i|`` and
``s' >= ||C'_i||_2`` (1 + 1e-9 for the rotation matrices flown here, checked
by the caller). Culling, clipping and the field of view are linear or
|linear| in ``q`` (gradient norms 1 and ``sec eta``); the exact culling
``(r - p) . n``, the elevation ``(r - p) . n >= |r - p| sin e_min`` and the
range ``|r - p| <= max_range`` move by at most ``|n| B_r``, ``(|n| + |sin
e_min|) B_r`` and ``B_r``. Illumination does not depend on the spacecraft.

So with a *budget* ``(B_C, B_r)`` fixed before any scenario:

* :func:`ideas_hpc.core.mapping.coverage.first_image_by_spacecraft` (the nominal witness)
  gives, per (candidate, vertex), the first nominal
  image that sees the vertex (-1: unseen), and :func:`reachable` whether any
  image could pass culling, clipping, field of view, elevation and range for
  some deviation within the budget (a superset test with floating-point slack);
* :func:`perturbed_rows` then decides each (candidate, vertex) of a scenario
  exactly: a nominally seen vertex is first tested at its witness image in
  the perturbed flight (one exact test: a hit settles it); a vertex that is
  not reachable stays unseen in every image where the deviation is within
  the budget, so only the images before ``i_ok`` (the first image from which
  the candidate's deviation stays within budget, e.g. after the closed-loop
  attitude has converged) are scanned; anything else gets the full exact scan
  of :func:`ideas_hpc.core.mapping.time_tree._scan` on the perturbed flight.

Every answer is either an exact test on the perturbed flight or a proof from
the bounds, so rows equal a full recomputation bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.mapping.time_tree import _FP, _classify, scan_tree
from ideas_hpc.core.mapping.coverage import _is_strict
from ideas_hpc.core.mapping.segments import face_blocks_cone
from ideas_hpc.core.mapping.visibility import _seen, _seen_hint
from ideas_hpc.core.mapping.records import TimeTree

#: Bound on ||C'||_2 for the flown rotation matrices (checked by the boundary layer).
S_MAX = 1.0 + 1e-9


@njit(cache=True, inline="always")
def _required(vtx, k, i, cam, sec_eta, opts, bc, br):
    """Smallest position deviation (m) with which a camera within ``bc`` of image ``i``
    could pass culling, clipping, field of view, elevation and range (inf: none).

    Each test is ``slack >= -(its change bound)``, linear in the deviation (module
    docstring), solved for it; ``br`` (the budget) only sizes the floating-point
    slack, and the result is shrunk by a relative and absolute 1e-9 so that it
    never exceeds the exact value. ``vtx`` is ``(px, py, pz, nx, ny, nz, |n|)`` (m, T).
    """
    px, py, pz, nx, ny, nz, nabs = vtx
    r_T = cam.r_T_m
    dcm_BT = cam.dcm_BT
    tan_eta = cam.tan_eta
    near = cam.near_m
    far = cam.far_m
    exact = cam.exact
    sin_min_elev = opts.sin_min_elev
    max_range = opts.max_range_m
    rx = r_T[k, i, 0]
    ry = r_T[k, i, 1]
    rz = r_T[k, i, 2]
    dx = px - rx
    dy = py - ry
    dz = pz - rz
    dn = np.sqrt(dx * dx + dy * dy + dz * dz)
    fp = _FP * (dn + br + np.sqrt(rx * rx + ry * ry + rz * rz))
    los_n = -(dx * nx + dy * ny + dz * nz)
    cul = los_n if exact else rx * nx + ry * ny + rz * nz
    if nabs > 0.0:
        need = (-cul - fp * nabs) / nabs
    else:
        need = 0.0 if cul >= 0.0 else np.inf
    qz = dcm_BT[k, i, 2, 0] * dx + dcm_BT[k, i, 2, 1] * dy + dcm_BT[k, i, 2, 2] * dz
    qx = dcm_BT[k, i, 0, 0] * dx + dcm_BT[k, i, 0, 1] * dy + dcm_BT[k, i, 0, 2] * dz
    qy = dcm_BT[k, i, 1, 0] * dx + dcm_BT[k, i, 1, 1] * dy + dcm_BT[k, i, 1, 2] * dz
    base = bc * dn + fp                     # delta = base + S_MAX * deviation
    need = max(need, (near - qz - base) / S_MAX, (qz - far - base) / S_MAX)
    fov = max(abs(qx), abs(qy)) - tan_eta * qz - (1.0 + tan_eta) * fp
    need = max(need, (fov / sec_eta - base) / S_MAX)
    if sin_min_elev > -1.0 or max_range < np.inf:
        need = max(need, dn - max_range - fp,
                   (dn * sin_min_elev - los_n - 2.0 * fp) / (nabs + abs(sin_min_elev)))
    return max(0.0, need * (1.0 - 1e-9) - 1e-9)


@njit(cache=True, inline="always")
def _could(vtx, k, i, cam, sec_eta, opts, bc, br):
    """False when no camera within ``(bc, br)`` of image ``i`` can pass the geometric tests."""
    return _required(vtx, k, i, cam, sec_eta, opts, bc, br) <= br


@njit(cache=True, inline="always")
def _extreme(tree, stack, k, vtx, cam, opts, bc, br, last):
    """First (``last``: last) image that :func:`_could` see the vertex ``vtx`` (as in
    :func:`_required`), -1 if none. ``tree`` carries the budget-inflated bounds."""
    NI = tree.NI
    sec_eta = tree.sec_eta
    px, py, pz, nx, ny, nz, nabs = vtx
    sp = 1
    stack[0] = NI.shape[0] - 1
    while sp > 0:
        sp -= 1
        node = stack[sp]
        if _classify(tree, k, node, px, py, pz, nx, ny, nz, nabs, cam) == 0:
            continue
        if NI[node, 2] >= 0:
            first, second = NI[node, 3], NI[node, 2]     # pushed second, popped first
            if last:
                first, second = NI[node, 2], NI[node, 3]
            if first >= 0:
                stack[sp] = first
                sp += 1
            if second >= 0:
                stack[sp] = second
                sp += 1
            continue
        n = NI[node, 1] - NI[node, 0]
        for h in range(n):
            i = NI[node, 1] - 1 - h if last else NI[node, 0] + h
            if _could(vtx, k, i, cam, sec_eta, opts, bc, br):
                return i
    return -1


@njit(cache=True, parallel=True)
def reachable(mesh, cam, opts, bc, br):
    """(N, V, 2) int64: first and last image at which a camera within the budget could
    see vertex j (-1, -1: none), and (N, V) the smallest position deviation (m, with
    the DCM deviation ``bc``) that could let any image of that window see it
    (:func:`_required`; inf when none).

    ``mesh``, ``cam`` (the nominal flight) and ``opts`` (only the elevation and
    range are read) as in :func:`ideas_hpc.core.mapping.coverage.coverage_vertices`.
    ``bc`` (Frobenius norm of the DCM deviation) and ``br`` (m, position
    deviation) is the budget; outside the window no camera within it passes
    culling, clipping, field of view, elevation and range (module docstring).
    The nominal time tree prunes with its node bounds inflated by the budget.
    """
    vertices = mesh.vertices_T_m
    normals = mesh.normals_T
    nv = vertices.shape[0]
    nsc = cam.r_T_m.shape[0]
    tree = TimeTree(*scan_tree(cam))
    NF = tree.NF
    for k in range(nsc):
        for node in range(tree.NI.shape[0]):
            NF[k, node, 14] = (NF[k, node, 14] + br) * S_MAX * (1.0 + 1e-12)
            NF[k, node, 13] = (NF[k, node, 13] + bc) * (1.0 + 1e-12)
    sec_eta = tree.sec_eta
    out = np.full((nsc, nv, 2), -1, dtype=np.int64)
    margin = np.full((nsc, nv), np.inf)
    for j in prange(nv):
        stack = np.empty(128, dtype=np.int64)
        px = vertices[j, 0]
        py = vertices[j, 1]
        pz = vertices[j, 2]
        nx = normals[j, 0]
        ny = normals[j, 1]
        nz = normals[j, 2]
        nabs = np.sqrt(nx * nx + ny * ny + nz * nz)
        vtx = (px, py, pz, nx, ny, nz, nabs)
        for k in range(nsc):
            lo = _extreme(tree, stack, k, vtx, cam, opts, bc, br, False)
            if lo >= 0:
                hi = _extreme(tree, stack, k, vtx, cam, opts, bc, br, True)
                out[k, j, 0] = lo
                out[k, j, 1] = hi
                m = np.inf
                for i in range(lo, hi + 1):
                    m = min(m, _required(vtx, k, i, cam, sec_eta, opts, bc, br))
                margin[k, j] = m
    return out, margin


@njit(cache=True, parallel=True)
def orthonormality_error(dcm_BT):
    """Largest ``||C C^T - I||_F`` over (N, n_img, 3, 3) DCMs (``||C||_2 <= sqrt(1 + it)``)."""
    nsc = dcm_BT.shape[0]
    nimg = dcm_BT.shape[1]
    worst = np.zeros(nsc)
    for k in prange(nsc):
        w = 0.0
        for i in range(nimg):
            g = 0.0
            for a in range(3):
                for c in range(3):
                    t = (dcm_BT[k, i, a, 0] * dcm_BT[k, i, c, 0]
                         + dcm_BT[k, i, a, 1] * dcm_BT[k, i, c, 1]
                         + dcm_BT[k, i, a, 2] * dcm_BT[k, i, c, 2])
                    if a == c:
                        t -= 1.0
                    g += t * t
            w = max(w, np.sqrt(g))
        worst[k] = w
    return worst.max() if nsc > 0 else 0.0


@njit(cache=True, parallel=True)
def deviation_start(r_nom, dcm_nom, r_T, dcm_BT, bc, br):
    """(N,) int64 first image from which every image's deviation is within ``(bc, br)``
    (``n_img`` when the last image is already outside), and (N,) the largest position
    deviation (m) from that image on."""
    nsc = r_T.shape[0]
    nimg = r_T.shape[1]
    out = np.empty(nsc, dtype=np.int64)
    dev = np.zeros(nsc)
    for k in prange(nsc):
        i_ok = 0
        dmax = 0.0
        for i in range(nimg - 1, -1, -1):
            dc = 0.0
            for a in range(3):
                for b in range(3):
                    dc += (dcm_BT[k, i, a, b] - dcm_nom[k, i, a, b]) ** 2
            dr = np.sqrt((r_T[k, i, 0] - r_nom[k, i, 0]) ** 2
                         + (r_T[k, i, 1] - r_nom[k, i, 1]) ** 2
                         + (r_T[k, i, 2] - r_nom[k, i, 2]) ** 2)
            if not (np.sqrt(dc) <= bc and dr <= br):
                i_ok = i + 1
                break
            dmax = max(dmax, dr)
        out[k] = i_ok
        dev[k] = dmax
    return out, dev


@njit(cache=True, inline="always")
def _below_elevation(NF, k, node, px, py, pz, nx, ny, nz, nabs, sin_min_elev, max_range):
    """True when every image of the node fails the elevation or the range test.

    With ``|r_k - r_m| <= e_r``: ``(r_k - p) . n <= (r_m - p) . n + |n| e_r`` and
    ``|r_k - p| >= |r_m - p| - e_r``.
    """
    vx = NF[k, node, 9] - px
    vy = NF[k, node, 10] - py
    vz = NF[k, node, 11] - pz
    dist = np.sqrt(vx * vx + vy * vy + vz * vz)
    er = NF[k, node, 14]
    fp = _FP * (dist + er + NF[k, node, 12])
    if dist - er - fp > max_range:
        return True
    if sin_min_elev <= 0.0:
        return False
    los_hi = vx * nx + vy * ny + vz * nz + nabs * er + fp
    return los_hi < (dist - er - fp) * sin_min_elev


@njit(cache=True, inline="always")
def _scan_range(j, k, a, b, tree, stack, hint, mesh, cam, strict, opts, bvh):
    """Does spacecraft ``k`` see vertex ``j`` in an image ``a <= i < b``? Exact.

    Walks the perturbed flight's time tree: a node failing culling or clipping
    with margin is skipped (:func:`~ideas_hpc.core.mapping.time_tree._classify`), and so
    is a node whose sight lines all lie in a cone the last blocking face
    ``hint[0]`` covers (:func:`~ideas_hpc.core.mapping.segments.face_blocks_cone`); leaf
    images are tested one by one (:func:`~ideas_hpc.core.mapping.visibility._seen_hint`).
    """
    NF = tree.NF
    NI = tree.NI
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
            vx = NF[k, node, 9] - px
            vy = NF[k, node, 10] - py
            vz = NF[k, node, 11] - pz
            dist = np.sqrt(vx * vx + vy * vy + vz * vz)
            er = NF[k, node, 14]
            if er < 0.5 * dist and face_blocks_cone(tri, tri_vid, hint[0], j, px, py, pz,
                                                    vx / dist, vy / dist, vz / dist,
                                                    np.arcsin(er / dist), dist - er):
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


@njit(cache=True, parallel=True)
def perturbed_rows(nominal, mesh, cam, opts, bvh):
    """(N, V) bool rows of the perturbed flight ``cam`` (module docstring).

    ``nominal`` is a :class:`~ideas_hpc.core.mapping.records.Nominal`: ``witness`` (N, V) from
    :func:`~ideas_hpc.core.mapping.coverage.first_image_by_spacecraft`, ``window`` (N, V, 2) and ``margin`` (N, V) from
    :func:`reachable` with the budget, ``i_ok`` and ``dev`` (N,) from
    :func:`deviation_start` with the same budget (a window is skipped when the
    candidate's largest deviation from ``i_ok`` on is below the margin); other
    arguments as :func:`ideas_hpc.core.mapping.coverage.observed_by_spacecraft`,
    for the perturbed flight. A (candidate, vertex) not settled by its
    witness image is scanned exactly over the images before ``i_ok`` and over
    its window from ``i_ok`` on (:func:`_scan_range`).
    """
    witness, window, margin, i_ok, dev = nominal
    nv = mesh.vertices_T_m.shape[0]
    nsc = cam.r_T_m.shape[0]
    tree = TimeTree(*scan_tree(cam))
    strict = _is_strict(opts)
    mask = np.zeros((nsc, nv), dtype=np.bool_)
    for j in prange(nv):
        stack = np.empty(128, dtype=np.int64)
        hint = np.full(1, -1, dtype=np.int64)
        for k in range(nsc):
            w = witness[k, j]
            if w >= 0 and _seen(j, k, w, mesh, cam, opts, bvh, opts.occlusion,
                                opts.illumination):
                mask[k, j] = True
                continue
            hint[0] = -1
            seen = _scan_range(j, k, 0, i_ok[k], tree, stack, hint, mesh, cam, strict, opts,
                               bvh)
            if not seen and window[k, j, 0] >= 0 and not dev[k] < margin[k, j]:
                seen = _scan_range(j, k, max(window[k, j, 0], i_ok[k]), window[k, j, 1] + 1,
                                   tree, stack, hint, mesh, cam, strict, opts, bvh)
            mask[k, j] = seen
    return mask
