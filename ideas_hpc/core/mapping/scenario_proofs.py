"""What the nominal flight proves for every flight within a deviation budget (issue 20).

A scenario moves every candidate's camera by a small deviation from its
nominal flight: positions ``r'_i = r_i + dr_i`` and camera DCMs
``C'_i = C_i + dC_i`` at the images. For a vertex ``p`` the camera
coordinates move by (same derivation as :mod:`ideas_hpc.core.mapping.time_tree`)::

    q'_i - q_i = (C'_i - C_i)(p - r_i) + C'_i (r_i - r'_i),
    |q'_i - q_i| <= B_C |p - r_i| + s' d,

with ``B_C >= ||C'_i - C_i||_F``, ``d = |r'_i - r_i|`` and ``s' >= ||C'_i||_2``
(:data:`S_MAX` for the rotation matrices flown here, checked by the caller).
Culling, clipping and the field of view are linear or ``|linear|`` in ``q``
(gradient norms 1 and ``sec eta``); the exact culling ``(r - p) . n``, the
elevation ``(r - p) . n >= |r - p| sin e_min`` and the range
``|r - p| <= max_range`` move by at most ``|n| d``, ``(|n| + |sin e_min|) d``
and ``d``. Each test ``slack >= 0`` thus holds for every deviation ``d`` below
``(slack - bound at d = 0) / (its rate)`` and fails for every ``d`` below
``(-slack - bound at d = 0) / rate``. Illumination does not depend on the
spacecraft. With the budget ``(B_C, B_r)``:

* :func:`windows`: per (candidate, vertex) the first and last image at which a
  camera within the budget (or with its position within ``B_r``, in any
  attitude) might see the vertex: every image outside fails the geometric
  tests for all such cameras (:func:`_required`), or one face blocks every
  sight line to them (the cone of half-angle ``asin(B_r / |r - p|)``,
  :func:`~ideas_hpc.core.mapping.segments.face_blocks_cone`);
* :func:`witness_proofs`: per nominally seen (candidate, vertex) a *witness*
  image, the nominally seeing image whose geometric tests keep the most slack
  (:func:`_slacks`), and its *proof*: the slack of its clipping and
  field-of-view tests in camera coordinates and a position radius (culling,
  elevation, range), capped where needed by an occlusion proof: no face meets
  the cone of sight lines from the vertex to every camera position within that
  radius (:func:`~ideas_hpc.core.mapping.bvh.cone_clear`). Any flight whose
  camera deviation at the witness satisfies both sees the vertex there.

Every bound carries floating-point slack (``_FP``) and results are shrunk by a
relative and absolute 1e-9, so a proof never claims what the exact per-image
test would deny: :func:`ideas_hpc.core.mapping.scenario_rows.perturbed_rows`
uses them to settle (candidate, vertex) pairs without testing them.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ideas_hpc.core.mapping.bvh import cone_clear
from ideas_hpc.core.mapping.records import TimeTree
from ideas_hpc.core.mapping.segments import face_blocks_cone, segment_hit
from ideas_hpc.core.mapping.time_tree import _AX, _FP, _below_elevation, _classify, scan_tree
from ideas_hpc.core.mapping.visibility import _seen

#: Bound on ||C'||_2 for the flown rotation matrices (checked by the boundary layer).
S_MAX = 1.0 + 1e-9
#: A DCM budget no attitude exceeds: ``||C' - C||_F <= ||C'||_F + ||C||_F <= 2 sqrt(3) S_MAX``.
BC_ANY = 2.0 * np.sqrt(3.0) * S_MAX * (1.0 + 1e-12)


@njit(cache=True, inline="always")
def _vertex(mesh, j):
    """``(px, py, pz, nx, ny, nz, |n|)`` of vertex ``j`` (m, frame T)."""
    p = mesh.vertices_T_m
    n = mesh.normals_T
    return (p[j, 0], p[j, 1], p[j, 2], n[j, 0], n[j, 1], n[j, 2],
            np.sqrt(n[j, 0] * n[j, 0] + n[j, 1] * n[j, 1] + n[j, 2] * n[j, 2]))


@njit(cache=True, inline="always")
def _camera_coords(vtx, k, i, cam, br):
    """Image ``i``'s view of the vertex ``vtx = (px, py, pz, nx, ny, nz, |n|)`` (m, T):
    ``(|p - r|, floating-point allowance sized for deviations up to br, (r - p) . n,
    the culling value (exact or paper), q_x, q_y, q_z)``, all m."""
    px, py, pz, nx, ny, nz, _ = vtx
    r_T = cam.r_T_m
    dcm_BT = cam.dcm_BT
    rx = r_T[k, i, 0]
    ry = r_T[k, i, 1]
    rz = r_T[k, i, 2]
    dx = px - rx
    dy = py - ry
    dz = pz - rz
    dn = np.sqrt(dx * dx + dy * dy + dz * dz)
    fp = _FP * (dn + br + np.sqrt(rx * rx + ry * ry + rz * rz))
    los_n = -(dx * nx + dy * ny + dz * nz)
    cul = los_n if cam.exact else rx * nx + ry * ny + rz * nz
    qx = dcm_BT[k, i, 0, 0] * dx + dcm_BT[k, i, 0, 1] * dy + dcm_BT[k, i, 0, 2] * dz
    qy = dcm_BT[k, i, 1, 0] * dx + dcm_BT[k, i, 1, 1] * dy + dcm_BT[k, i, 1, 2] * dz
    qz = dcm_BT[k, i, 2, 0] * dx + dcm_BT[k, i, 2, 1] * dy + dcm_BT[k, i, 2, 2] * dz
    return dn, fp, los_n, cul, qx, qy, qz


@njit(cache=True, inline="always")
def _required(vtx, k, i, cam, sec_eta, opts, bc, br):
    """Smallest position deviation (m) with which a camera within ``bc`` of image ``i``
    could pass culling, clipping, field of view, elevation and range (inf: none).

    Each test is ``slack >= -(its change bound)``, linear in the deviation (module
    docstring), solved for it; ``br`` (the budget) only sizes the floating-point
    slack, and the result is shrunk by a relative and absolute 1e-9 so that it
    never exceeds the exact value. ``vtx`` is ``(px, py, pz, nx, ny, nz, |n|)`` (m, T).
    """
    nabs = vtx[6]
    sin_min_elev = opts.sin_min_elev
    max_range = opts.max_range_m
    dn, fp, los_n, cul, qx, qy, qz = _camera_coords(vtx, k, i, cam, br)
    if nabs > 0.0:
        need = (-cul - fp * nabs) / nabs
    else:
        need = 0.0 if cul >= 0.0 else np.inf
    base = bc * dn + fp                     # delta = base + S_MAX * deviation
    need = max(need, (cam.near_m - qz - base) / S_MAX, (qz - cam.far_m - base) / S_MAX)
    fov = max(abs(qx), abs(qy)) - cam.tan_eta * qz - (1.0 + cam.tan_eta) * fp
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
def _slacks(vtx, k, i, cam, sec_eta, opts, br):
    """How far image ``i``'s geometric tests are from failing (module docstring).

    Returns ``(slack_q, radius, dist)``: the clipping and field-of-view tests
    hold for every camera with ``B_C |p - r| + S_MAX d < slack_q`` (m, in camera
    coordinates); culling, elevation and range hold for every position
    deviation ``d < radius`` (m, inf: none depends on it); ``dist = |p - r|``.
    Floating-point allowances are sized for ``d <= br``; both are shrunk by a
    relative and absolute 1e-9 (-inf: some test fails already).
    """
    nabs = vtx[6]
    sin_min_elev = opts.sin_min_elev
    max_range = opts.max_range_m
    tan_eta = cam.tan_eta
    dn, fp, los_n, cul, qx, qy, qz = _camera_coords(vtx, k, i, cam, br)
    if nabs > 0.0:
        rad = (cul - fp * nabs) / nabs
    else:
        rad = np.inf if (cul > 0.0 or not cam.exact) else -np.inf
    if sin_min_elev > -1.0 or max_range < np.inf:
        rad = min(rad, max_range - dn - fp,
                  (los_n - dn * sin_min_elev - 2.0 * fp) / (nabs + abs(sin_min_elev)))
    fov = tan_eta * qz - max(abs(qx), abs(qy)) - (1.0 + tan_eta) * fp
    slack = min(qz - cam.near_m - fp, cam.far_m - qz - fp, fov / sec_eta - fp)
    return slack * (1.0 - 1e-9) - 1e-9, rad * (1.0 - 1e-9) - 1e-9, dn


#: Images between the scores :func:`witness_proofs` evaluates before it refines around
#: the best (1: every image). On the main job's bank (eros001708, 720 candidates, two
#: threads): 1 -> 8 -> 32 took the proofs from 1.54 to 0.58 to 0.40 s, the rows'
#: time unchanged (0.105, 0.103 s per scenario).
WITNESS_STRIDE = 32


@njit(cache=True, inline="always")
def _best_slack(vtx, k, a, b, stride, cam, sec_eta, opts, bc, br):
    """The image of ``a, a + stride, ... < b`` whose geometric tests keep the most
    slack at the budget ``(bc, br)`` (:func:`_slacks`; ``a`` when none is better)."""
    best = -np.inf
    b_i = a
    for i in range(a, b, stride):
        sq, rad, dn = _slacks(vtx, k, i, cam, sec_eta, opts, br)
        score = min(sq - bc * dn, S_MAX * rad)      # slack left at the budget
        if score > best:
            best = score
            b_i = i
    return b_i


@njit(cache=True, parallel=True)
def witness_proofs(first, window, mesh, cam, opts, bvh, bc, br):
    """Witness images and their proofs (module docstring).

    ``first`` (N, V): the first nominal image that sees each vertex (-1: none,
    :func:`~ideas_hpc.core.mapping.coverage.first_image_by_spacecraft`);
    ``window`` (N, V, 2) from :func:`windows` with the budget ``(bc, br)``;
    ``mesh``, ``cam`` (the nominal flight), ``opts``, ``bvh`` as in
    :func:`ideas_hpc.core.mapping.coverage.coverage_vertices`.

    Returns ``witness`` (N, V) int64, ``slack_q`` and ``radius`` (N, V) float64, m.
    The witness is the image of ``[first, window end]`` whose geometric tests
    keep the most slack at the budget (:func:`_slacks`; a search every
    :data:`WITNESS_STRIDE` images refined around the best) if the full nominal test
    (:func:`~ideas_hpc.core.mapping.visibility._seen`) passes there, else
    ``first``. A flight whose camera at the witness has DCM deviation ``c``
    (Frobenius) and position deviation ``d`` sees the vertex there when
    ``d < radius`` and ``c (|p - r'| + d) + S_MAX d < slack_q`` (``r'`` the
    flown position; ``|p - r| <= |p - r'| + d``): ``radius`` is the
    position-only tests' radius, capped at ``br`` and, with occlusion, at a
    radius whose cone of sight lines no face meets
    (:func:`~ideas_hpc.core.mapping.bvh.cone_clear`). Unseen: (-1, -inf, 0).
    """
    nv = mesh.vertices_T_m.shape[0]
    nsc = cam.r_T_m.shape[0]
    witness = np.full((nsc, nv), -1, dtype=np.int64)
    slack_q = np.full((nsc, nv), -np.inf)
    radius = np.zeros((nsc, nv))
    for j in prange(nv):
        _vertex_witnesses(np.int64(j), first, window, mesh, cam, opts, bvh, bc, br, witness,
                          slack_q, radius)
    return witness, slack_q, radius


@njit(cache=True)
def _vertex_witnesses(j, first, window, mesh, cam, opts, bvh, bc, br, witness, slack_q,
                      radius):
    """Vertex ``j``'s witnesses of :func:`witness_proofs`, every candidate, into
    ``witness[:, j]``, ``slack_q[:, j]`` and ``radius[:, j]``.

    The kernel's ``prange`` body, compiled on its own (as
    :func:`~ideas_hpc.core.mapping.scenario_rows._candidate_row` is, for the same reason).
    """
    nsc = cam.r_T_m.shape[0]
    r_T = cam.r_T_m
    sec_eta = np.sqrt(1.0 + cam.tan_eta * cam.tan_eta) * (1.0 + 1e-12)
    vtx = _vertex(mesh, j)
    px, py, pz = vtx[0], vtx[1], vtx[2]
    for k in range(nsc):
        w = first[k, j]
        if w < 0:
            continue
        # the score varies smoothly along the pass: every WITNESS_STRIDE-th image,
        # then the images around the best (speed only: any seeing image is a witness)
        end = window[k, j, 1] + 1
        a, b, stride = w, end, WITNESS_STRIDE
        for _ in range(2):   # one call site: the inlined search is compiled once
            b_i = _best_slack(vtx, k, a, b, stride, cam, sec_eta, opts, bc, br)
            a, b, stride = max(w, b_i - WITNESS_STRIDE + 1), min(end, b_i + WITNESS_STRIDE), 1
        if b_i != w and not _seen(j, k, b_i, mesh, cam, opts, bvh, opts.occlusion,
                                  opts.illumination):
            b_i = w
        witness[k, j] = b_i
        sq, rad, dn = _slacks(vtx, k, b_i, cam, sec_eta, opts, br)
        slack_q[k, j] = sq
        rad = min(rad, br)
        if opts.occlusion and rad > 0.0:
            ax = (r_T[k, b_i, 0] - px) / dn
            ay = (r_T[k, b_i, 1] - py) / dn
            az = (r_T[k, b_i, 2] - pz) / dn
            # the sight lines p -> r' with |r' - r| <= rad lie in this cone
            while rad > 1e-3 * br and not (
                    rad < 0.5 * dn and cone_clear(
                        bvh.node_bounds_m, bvh.node_info, bvh.tri_m, bvh.tri_vid,
                        px, py, pz, ax, ay, az, np.arcsin(rad / dn), np.int64(j))):
                rad *= 0.125
            if rad <= 1e-3 * br:
                rad = 0.0
        radius[k, j] = max(rad, 0.0)


@njit(cache=True, inline="always")
def _cone_blocked(bvh, f, j, px, py, pz, cx, cy, cz, e):
    """Face ``f`` blocks every segment from vertex ``j`` at ``p`` to a point within
    ``e`` (m) of ``c`` (such segments lie in the cone around ``c - p`` of half-angle
    ``asin(e / |c - p|)`` and are at least ``|c - p| - e`` long)."""
    vx = cx - px
    vy = cy - py
    vz = cz - pz
    dist = np.sqrt(vx * vx + vy * vy + vz * vz)
    return e < 0.5 * dist and face_blocks_cone(bvh.tri_m, bvh.tri_vid, f, j, px, py, pz,
                                               vx / dist, vy / dist, vz / dist,
                                               np.arcsin(e / dist), dist - e)


@njit(cache=True, inline="always")
def _walk(tree, stack, k, j, vtx, cam, opts, bvh, budget, last):
    """First (``last``: last) image at which a camera of candidate ``k`` within the
    ``budget`` ``(bc, br)`` might see vertex ``j`` (-1: none), see :func:`windows`."""
    NF = tree.NF
    NI = tree.NI
    bc, br = budget
    px, py, pz, nx, ny, nz, nabs = vtx
    r_T = cam.r_T_m
    e_img = br * (1.0 + 1e-12)
    elev = opts.sin_min_elev > -1.0 or opts.max_range_m < np.inf
    hint = np.int64(-1)
    sp = 1
    stack[0] = NI.shape[0] - 1
    while sp > 0:
        sp -= 1
        node = stack[sp]
        if _classify(tree, k, node, px, py, pz, nx, ny, nz, nabs, cam) == 0:
            continue
        if elev and _below_elevation(NF, k, node, px, py, pz, nx, ny, nz, nabs,
                                     opts.sin_min_elev, opts.max_range_m):
            continue
        if opts.occlusion and hint >= 0 and _cone_blocked(
                bvh, hint, j, px, py, pz, NF[k, node, 9], NF[k, node, 10], NF[k, node, 11],
                NF[k, node, 14]):
            continue
        if NI[node, 2] >= 0:
            first, second = NI[node, 3], NI[node, 2]     # pushed first, popped second
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
            if not _could(vtx, k, i, cam, tree.sec_eta, opts, bc, br):
                continue
            if opts.occlusion:
                f = segment_hit(bvh, px, py, pz, r_T[k, i, 0] - px, r_T[k, i, 1] - py,
                                r_T[k, i, 2] - pz, 1.0, np.int64(j), hint)
                if f >= 0 and _cone_blocked(bvh, f, j, px, py, pz, r_T[k, i, 0], r_T[k, i, 1],
                                            r_T[k, i, 2], e_img):
                    hint = f
                    continue
            return i
    return -1


@njit(cache=True, parallel=True)
def windows(mesh, cam, opts, bvh, bc, br, both):
    """(N, V, 2) int64: the first and (with ``both``) last image at which a camera of
    candidate k within the budget ``(bc, br)`` of its nominal flight might see
    vertex j (-1: none; without ``both`` the last is -1).

    Outside the window every image fails culling, clipping, field of view,
    elevation or range for all those cameras, or, with occlusion, one face
    blocks all their sight lines (module docstring). ``bc =`` :data:`BC_ANY`:
    any attitude. The nominal time tree is walked in image order (backwards for
    the last) with its node bounds inflated by the budget; a node whose
    sight-line cone the last blocking face covers is skipped whole.
    """
    nv = mesh.vertices_T_m.shape[0]
    nsc = cam.r_T_m.shape[0]
    tree = TimeTree(*scan_tree(cam))
    NF = tree.NF
    for k in range(nsc):
        for node in range(tree.NI.shape[0]):
            NF[k, node, 14] = (NF[k, node, 14] + br) * S_MAX * (1.0 + 1e-12)
            NF[k, node, 13] = (NF[k, node, 13] + bc) * (1.0 + 1e-12)
            # per camera axis (time_tree_build): a row of C' - C_m grows by at most
            # bc, |r' - r_m| by br, and |row_a(C_m) . (r' - r_m)| by |row_a(C_m)| br
            # <= S br
            for a in range(3):
                NF[k, node, _AX + a] = (NF[k, node, _AX + a] + bc) * (1.0 + 1e-12)
                NF[k, node, _AX + 4 + a] = ((NF[k, node, _AX + 4 + a] + NF[k, node, 15] * br)
                                            * (1.0 + 1e-12))
            NF[k, node, _AX + 3] = (NF[k, node, _AX + 3] + br) * (1.0 + 1e-12)
    out = np.full((nsc, nv, 2), -1, dtype=np.int64)
    for j in prange(nv):
        _vertex_windows(np.int64(j), tree, mesh, cam, opts, bvh, bc, br, both, out)
    return out


@njit(cache=True)
def _vertex_windows(j, tree, mesh, cam, opts, bvh, bc, br, both, out):
    """Vertex ``j``'s windows of :func:`windows`, every candidate, into ``out[:, j]``.

    The kernel's ``prange`` body, compiled on its own (as
    :func:`~ideas_hpc.core.mapping.scenario_rows._candidate_row` is, for the same reason).
    """
    stack = np.empty(128, dtype=np.int64)
    vtx = _vertex(mesh, j)
    for k in range(cam.r_T_m.shape[0]):
        # the first image, then (with ``both``, when there is a first) the last: one
        # call site, so the inlined walk is compiled once (twice cost 48 s of compile)
        for last in range(2):
            if last == 1 and not (both and out[k, j, 0] >= 0):
                break
            out[k, j, last] = _walk(tree, stack, k, j, vtx, cam, opts, bvh, (bc, br),
                                    last == 1)
