"""Mapping boundary: validate inputs, pick the coverage kernel, package results (SPEC section 6).

Physics lives in :mod:`ideas_hpc.core.mapping.coverage` (culling, clipping, strict
options) and :mod:`ideas_hpc.core.mapping.bvh` (occlusion structure). This module
checks the arguments (raising :class:`~ideas_hpc.base.errors.InputError` that names
the argument), converts config units (deg, um, cm) to SI, builds the BVH when an
option needs it, and chooses the kernel:

* no strict option: :func:`~ideas_hpc.core.mapping.coverage.coverage_counts`
  (``prange`` over vertices, a time tree of image runs with rigorous motion
  bounds accepts or skips whole runs; early-out when counts are not wanted);
* a strict option: :func:`~ideas_hpc.core.mapping.coverage.coverage_vertices`
  (same time tree for pruning, ray queries per image, early-out when counts
  are not wanted).

* the quality pass (issue 14: options ``quality`` or any requirement):
  :func:`~ideas_hpc.core.mapping.quality.quality_vertices` (same visibility tests,
  every observation visited, plus light, resolution, angles and stereo). It
  runs only when asked for; paper and strict runs without it go through the
  kernels above unchanged.

Results map onto the store variables of SPEC section 9: ``observed``,
``first_seen`` (s, NaN never), ``times_seen``, ``coverage``, ``coverage_count``,
``coverage_seen`` and, with the quality pass, the :class:`QualityResult` fields.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.core.mapping import bvh as _bvh
from ideas_hpc.core.mapping import coverage as _cov
from ideas_hpc.core.mapping import quality as _qual
from ideas_hpc.core.mapping import quality_masks as _qmask
from ideas_hpc.core.mapping import stereo_pairs as _pairs
from ideas_hpc.core.mapping.records import Bvh, Camera, Mesh, Quality, Strict
from ideas_hpc.mapping.options import CoverageOptions, _finite, frustum_of
from ideas_hpc.base.errors import InputError
from ideas_hpc.engine.variables import QUALITY, VARS
#: Tolerance on ``C C^T = I`` for camera DCMs.
DCM_ORTHO_TOL = 1e-6


@dataclass
class CoverageResult:
    """Per-vertex coverage of one flyby (store variables of SPEC section 9).

    Attributes
    ----------
    observed : (V,) bool
    first_seen : (V,) float64
        s, NaN for vertices never seen.
    times_seen : (V,) int32
        (spacecraft, image) pairs that saw the vertex; with ``counts=False``
        only 0/1.
    coverage : float
        Observed area / total area, 0..1.
    coverage_count : float
        Observed vertices / all vertices.
    coverage_seen : float or None
        Observed area / total area; ``coverage`` is the mapped fraction when a
        requirement is set, else the same number. None means ``coverage``.
    quality : QualityResult or None
        The quality pass, when it ran.
    """

    observed: np.ndarray
    first_seen: np.ndarray
    times_seen: np.ndarray
    coverage: float
    coverage_count: float
    coverage_seen: float | None = None
    quality: "QualityResult | None" = None

    def __post_init__(self):
        if self.coverage_seen is None:
            self.coverage_seen = self.coverage


@dataclass
class QualityResult:
    """Per-vertex observation quality (issue 14; :mod:`ideas_hpc.core.mapping.quality`). SI.

    Attributes
    ----------
    lit : (V,) bool
        Sunlit and not shadowed at some observation.
    best_resolution : (V,) float64
        Smallest ``rho * range / cos(emission)`` over the observations, m
        (NaN: never observed, inf: only seen from below the local horizon).
    emission_at_best, incidence_at_best, phase_at_best : (V,) float64
        rad, at the best-resolution observation (NaN: never observed).
    n_spacecraft_seen : (V,) int32
    stereo : (V,) bool
        Two usable observations with a convergence angle in the stereo range.
    mapped : (V,) bool
        Meets the coverage requirement.
    """

    lit: np.ndarray
    best_resolution: np.ndarray
    emission_at_best: np.ndarray
    incidence_at_best: np.ndarray
    phase_at_best: np.ndarray
    n_spacecraft_seen: np.ndarray
    stereo: np.ndarray
    mapped: np.ndarray


def _check_geometry(shape, r_T, dcm_BT, eta, near, far, active=None):
    """Validate and convert; return contiguous float64 arrays and scalars."""
    eta = _finite(eta, "eta")
    if not 0.0 < eta < math.pi / 2:
        raise InputError(f"half angle must be in (0, 90) deg, got {math.degrees(eta):g} deg",
                         field="eta")
    near = _finite(near, "near")
    far = _finite(far, "far")
    if near <= 0.0:
        raise InputError(f"must be > 0 m, got {near:g}", field="near")
    if near >= far:
        raise InputError(f"near ({near:g} m) must be smaller than far ({far:g} m)",
                         field="near")
    r = np.asarray(r_T, dtype=np.float64)
    if r.ndim != 3 or r.shape[2] != 3 or r.shape[0] < 1 or r.shape[1] < 1:
        raise InputError(f"must have shape (N, n_img, 3), got {r.shape}", field="r_T")
    if not np.all(np.isfinite(r)):
        raise InputError("has non-finite values", field="r_T")
    c = np.asarray(dcm_BT, dtype=np.float64)
    if c.shape != r.shape[:2] + (3, 3):
        raise InputError(f"must have shape {r.shape[:2] + (3, 3)} to match r_T, got {c.shape}",
                         field="dcm_BT")
    c = np.ascontiguousarray(c)
    n_bad, err, i_err, det, i_det = _cov.dcm_check(c.reshape(-1, 3, 3))
    if n_bad:
        raise InputError("has non-finite values", field="dcm_BT")
    if err > DCM_ORTHO_TOL:
        k, i = np.unravel_index(i_err, c.shape[:2])
        raise InputError(f"not orthonormal at spacecraft {k}, image {i} "
                         f"(|C C^T - I| = {err:.2e})", field="dcm_BT")
    if det < 0.0:
        k, i = np.unravel_index(i_det, c.shape[:2])
        raise InputError(f"is a reflection (det < 0) at spacecraft {k}, image {i}",
                         field="dcm_BT")
    if active is None:
        act = np.ones(r.shape[0], dtype=np.bool_)
    else:
        act = np.asarray(active)
        if act.shape != (r.shape[0],):
            raise InputError(f"must have shape ({r.shape[0]},) to match r_T, got {act.shape}",
                             field="active")
        if act.dtype != np.bool_:
            raise InputError(f"must be a boolean mask, got dtype {act.dtype}", field="active")
        act = np.ascontiguousarray(act)
    return (np.ascontiguousarray(r), np.ascontiguousarray(c), math.tan(eta), near, far, act)


def _mesh(shape) -> Mesh:
    return Mesh(np.ascontiguousarray(shape.vertices_T, dtype=np.float64),
                np.ascontiguousarray(shape.vertex_normals_T, dtype=np.float64),
                np.ascontiguousarray(shape.vertex_areas, dtype=np.float64))


def _camera(r, c, t, tan_eta, near, far, exact) -> Camera:
    """The kernels' camera record from checked arrays (scalars typed as the record says)."""
    return Camera(r, c, t, float(tan_eta), float(near), float(far), bool(exact))


_BVH_CACHE: dict = {}


def occlusion_structure(shape):
    """The BVH of ``shape`` (built once per Shape object and cached)."""
    key = id(shape)
    hit = _BVH_CACHE.get(key)
    if hit is not None and hit[0] is shape:
        return hit[1]
    tree = Bvh(*_bvh.build_bvh(np.ascontiguousarray(shape.vertices_T, dtype=np.float64),
                               np.ascontiguousarray(shape.faces, dtype=np.int64)))
    if len(_BVH_CACHE) > 16:
        _BVH_CACHE.clear()
    _BVH_CACHE[key] = (shape, tree)
    return tree


_EMPTY_TREE = Bvh(np.zeros((1, 6)), np.full((1, 4), -1, dtype=np.int64),
                  np.zeros((1, 9)), np.zeros((1, 3), dtype=np.int64))


def _strict_args(shape, options: CoverageOptions, sun_T, n_img) -> tuple[Strict, Bvh]:
    """The kernels' :class:`Strict` options and the mesh's :class:`Bvh` (a dummy when unread)."""
    if options.needs_sun:
        if sun_T is None:
            raise InputError("illumination and the quality pass need the Sun direction per "
                         "image", field="sun_T")
        s = np.asarray(sun_T, dtype=np.float64)
        if s.ndim == 1 and s.shape == (3,):
            s = np.broadcast_to(s, (n_img, 3))
        if s.shape != (n_img, 3):
            raise InputError(f"must have shape ({n_img}, 3) (one per image), got {s.shape}",
                             field="sun_T")
        if not np.all(np.isfinite(s)):
            raise InputError("has non-finite values", field="sun_T")
        nrm = np.linalg.norm(s, axis=1)
        if np.any(nrm == 0.0):
            raise InputError("has a zero vector", field="sun_T")
        s = np.ascontiguousarray(s / nrm[:, None])
    else:
        s = np.zeros((1, 3))
    tree = occlusion_structure(shape) if (options.occlusion or options.needs_sun) \
        else _EMPTY_TREE
    sin_e = -2.0 if options.min_elevation_rad is None else math.sin(options.min_elevation_rad)
    return Strict(float(sin_e), float(options.max_range), bool(options.occlusion),
                  bool(options.illumination), s), tree


#: The boundary's checks and record builders, public for the layers above that
#: build the same records for their own kernels (the scenario rows).
check_geometry, mesh_record, camera_record, strict_records = (
    _check_geometry, _mesh, _camera, _strict_args)


def compute_coverage(shape, r_T, dcm_BT, image_times, *frustum,
                     options: CoverageOptions = CoverageOptions(), sun_T=None,
                     active=None, counts: bool = True) -> CoverageResult:
    """Coverage of a flyby: per-vertex observed, first-seen time and counts.

    Parameters
    ----------
    shape : ideas_hpc.body.shape.Shape
    r_T : (N, n_img, 3) array
        Spacecraft positions in T per image, m.
    dcm_BT : (N, n_img, 3, 3) array
        Camera DCM (B <- T) per image, camera along +z_B.
    image_times : (n_img,) array
        s, non-decreasing.
    *frustum : Frustum, or eta, near, far
        The camera's view (:class:`~ideas_hpc.mapping.options.Frustum`), or its
        three numbers: the half angle of the square field of view, rad, in
        (0, pi/2), and the clipping distances, m, ``0 < near < far``.
    options : CoverageOptions
    sun_T : (n_img, 3) or (3,) array, optional
        Direction body -> Sun in T (any length); needed for illumination.
    active : (N,) bool, optional
        False marks a failed spacecraft (its images are ignored).
    counts : bool
        True: full ``times_seen``. False: union and first-seen only, with
        early-out (faster; ``times_seen`` is then 0/1).

    Returns
    -------
    CoverageResult
    """
    eta, near, far = frustum_of(frustum)
    r, c, tan_eta, near, far, act = _check_geometry(shape, r_T, dcm_BT, eta, near, far, active)
    t = np.asarray(image_times, dtype=np.float64)
    if t.shape != (r.shape[1],):
        raise InputError(f"must have shape ({r.shape[1]},) to match r_T, got {t.shape}",
                         field="image_times")
    if not np.all(np.isfinite(t)):
        raise InputError("has non-finite values", field="image_times")
    if np.any(np.diff(t) < 0.0):
        raise InputError("must be non-decreasing", field="image_times")
    t = np.ascontiguousarray(t)
    mesh = _mesh(shape)
    cam = _camera(r, c, t, tan_eta, near, far, options.mode == "exact")
    if options.wants_quality:
        return _quality(shape, options, sun_T, mesh, cam, act, counts)
    if not options.strict:
        out = _cov.coverage_counts(mesh, cam, act, bool(counts))
    else:
        opts, bvh = _strict_args(shape, options, sun_T, r.shape[1])
        out = _cov.coverage_vertices(mesh, cam, act, bool(counts), opts, bvh)
    obs, first, times, cov, cov_n = out
    return CoverageResult(observed=obs, first_seen=first, times_seen=times,
                          coverage=float(cov), coverage_count=float(cov_n))


def _quality_record(options) -> Quality:
    return Quality(float(options.rho), np.ascontiguousarray(options.limits, dtype=np.float64),
                   bool(options.require_lit))


#: The kernels' :class:`Quality` record of coverage options (public for the world bank's
#: rows, :mod:`ideas_hpc.mapping.world_rows`).
quality_record = _quality_record


def _quality(shape, options, sun_T, mesh, cam, act, counts) -> CoverageResult:
    opts, bvh = _strict_args(shape, options, sun_T, cam.r_T_m.shape[1])
    (times, first, lit, res, emi, inc, pha, nsc, stereo,
     mapped) = _qual.quality_vertices(mesh, cam, act, opts, bvh, _quality_record(options),
                                      bool(options.require_stereo))
    a = mesh.areas_m2
    obs = times > 0
    seen, seen_n = _cov.coverage_fractions(obs, a)
    cov, cov_n = _cov.coverage_fractions(mapped, a)
    if not counts:
        times = obs.astype(np.int32)
    q = QualityResult(lit=lit, best_resolution=res, emission_at_best=emi,
                      incidence_at_best=inc, phase_at_best=pha, n_spacecraft_seen=nsc,
                      stereo=stereo, mapped=mapped)
    return CoverageResult(observed=obs, first_seen=first, times_seen=times,
                          coverage=float(cov), coverage_count=float(cov_n),
                          coverage_seen=float(seen), quality=q)


def observed_per_spacecraft(shape, r_T, dcm_BT, eta, near, far, *,
                            options: CoverageOptions = CoverageOptions(),
                            sun_T=None) -> np.ndarray:
    """(N, V) bool: vertex j seen by spacecraft k at any image (for the GA's subset unions).

    Arguments as in :func:`compute_coverage` (no times: each scan stops at its
    first hit).
    """
    r, c, tan_eta, near, far, _ = _check_geometry(shape, r_T, dcm_BT, eta, near, far)
    opts, bvh = _strict_args(shape, options, sun_T, r.shape[1])
    cam = _camera(r, c, np.zeros(r.shape[1]), tan_eta, near, far, options.mode == "exact")
    return _cov.observed_by_spacecraft(_mesh(shape), cam, opts, bvh)


def _per_spacecraft_args(shape, r_T, dcm_BT, image_times, eta, near, far, options, sun_T):
    r, c, tan_eta, near, far, _ = _check_geometry(shape, r_T, dcm_BT, eta, near, far)
    t = np.ascontiguousarray(np.asarray(image_times, dtype=np.float64))
    if t.shape != (r.shape[1],):
        raise InputError(f"must have shape ({r.shape[1]},) to match r_T, got {t.shape}",
                         field="image_times")
    opts, bvh = _strict_args(shape, options, sun_T, r.shape[1])
    return (_mesh(shape), _camera(r, c, t, tan_eta, near, far, options.mode == "exact"), opts,
            bvh, _quality_record(options))


def quality_per_spacecraft(shape, r_T, dcm_BT, image_times, eta, near, far, *,
                           options: CoverageOptions, sun_T=None) -> dict:
    """What each spacecraft alone maps, for the designers' unions (issue 14 item 4).

    Arguments as in :func:`compute_coverage`. Returns ``usable``, ``stereo``
    ((N, V) bool: a usable observation / a stereo pair from its own track) and
    ``resolution`` ((N, V) m, inf where unobserved); see
    :mod:`ideas_hpc.core.mapping.quality_masks`. ``mapped`` is ``usable`` and, with
    ``require_stereo``, ``stereo``: the per-spacecraft requirement mask.
    """
    usable, stereo, res = _qmask.quality_by_spacecraft(*_per_spacecraft_args(
        shape, r_T, dcm_BT, image_times, eta, near, far, options, sun_T))
    mapped = usable & stereo if options.require_stereo else usable
    return {"usable": usable, "stereo": stereo, "resolution": res, "mapped": mapped}


def stereo_pair_table(shape, r_T, dcm_BT, image_times, eta, near, far, *,
                      options: CoverageOptions, sun_T=None) -> np.ndarray:
    """(N (N - 1) / 2, V) bool: spacecraft pair ``a < b`` maps the vertex in stereo.

    Rows in :func:`ideas_hpc.core.mapping.stereo_pairs.pair_index` order; see that
    module. A swarm's stereo set is the union of its members' own-track
    ``stereo`` rows (:func:`quality_per_spacecraft`) and of its pairs' rows.
    """
    return _pairs.stereo_pairs(*_per_spacecraft_args(
        shape, r_T, dcm_BT, image_times, eta, near, far, options, sun_T))


def coverage_from_mask(mask, vertex_areas) -> tuple[float, float]:
    """(area coverage, count coverage) of the union of rows of a per-spacecraft mask."""
    m = np.asarray(mask, dtype=np.bool_)
    obs = m.any(axis=0) if m.ndim == 2 else m
    a = np.asarray(vertex_areas, dtype=np.float64)
    if obs.shape != a.shape:
        raise InputError(f"mask has {obs.shape[0]} vertices but vertex_areas {a.shape[0]}",
                         field="mask")
    cov, cov_n = _cov.coverage_fractions(np.ascontiguousarray(obs), np.ascontiguousarray(a))
    return float(cov), float(cov_n)


#: Quality-pass variables (per vertex) and their dtypes (declared in :mod:`ideas_hpc.engine.variables`).
QUALITY_VARS = {name: VARS[name].dtype for name in QUALITY}


def quality_arrays(cov) -> dict:
    """name -> (V,) array of a :class:`~ideas_hpc.mapping.coverage.CoverageResult`'s quality pass."""
    q = cov.quality
    if q is None:
        return {}
    return {name: np.asarray(getattr(q, name), dtype=dt) for name, dt in QUALITY_VARS.items()}
