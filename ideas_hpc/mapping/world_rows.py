"""Boundary of the world bank's row kernels (issue 43): one world's statics, then rows.

A world of a target prior (SPEC 7f) is flown by every candidate of its scenario around
one mesh under one Sun, so what the rows read of the world is built once and shared
(:class:`WorldStatics`): the kernels' mesh record (vertices, unit normals, areas), the
strict options with the Sun at the images, the BVH, the lighting table
(:func:`ideas_hpc.core.mapping.world_statics.lit_at_images`: lit at each image, which
does not depend on the candidate) and each vertex's clear cone
(:func:`~ideas_hpc.core.mapping.world_statics.clear_cones`: sight lines inside it need
no occlusion ray). :func:`rows_of_world` then gives the rows of any flight
through that world, identical to :func:`ideas_hpc.design.candidates.rows_from_views`:

* seen rows (no requirement): the early-out per-candidate scan
  (:func:`~ideas_hpc.core.mapping.coverage.observed_by_spacecraft`), the kernel the full
  path calls, on the shared records;
* mapped rows (a requirement without stereo):
  :func:`~ideas_hpc.core.mapping.world_rows.mapped_by_spacecraft`, each candidate's first
  usable image instead of every observation;
* a stereo requirement: the quality pass on the shared records
  (:func:`~ideas_hpc.core.mapping.quality_masks.quality_by_spacecraft`; stereo needs every
  usable direction).

The flight's arrays are validated as the full path validates them
(:func:`~ideas_hpc.mapping.coverage.check_geometry`: the same errors, by field).

With ``device="cuda"`` (the run's ``run.device``, :mod:`ideas_hpc.attitude.device`) the
mapped rows run as the ``numba.cuda`` kernel of
:mod:`ideas_hpc.core.mapping.world_rows_cuda` (one thread per row bit, the same test per
image); seen and stereo rows stay on the CPU (docs/gpu.md).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ideas_hpc.attitude.device import check_device
from ideas_hpc.core.mapping import world_rows as _wr
from ideas_hpc.core.mapping import world_statics as _ws
from ideas_hpc.core.mapping.coverage import observed_by_spacecraft
from ideas_hpc.core.mapping.observations import quality_tests
from ideas_hpc.core.mapping.quality_masks import quality_by_spacecraft
from ideas_hpc.core.mapping.records import Bvh, Mesh, QualityTests, Strict
from ideas_hpc.mapping.coverage import (camera_record, check_geometry, mesh_record,
                                        quality_record, strict_records)
from ideas_hpc.mapping.options import CoverageOptions

__all__ = ["WorldStatics", "rows_of_world", "world_statics"]

#: Half-angle cap of the clear cones, rad (speed only: sight lines outside cast rays, and
#: a wider cap walks more of the BVH per vertex: on the Eros-class prior 1.5 rad is best
#: at 642 vertices and 720 candidates, 0.141 against 0.146 s, and 1.1 rad at 10242
#: vertices and 180 candidates, 0.94 against 1.10 s; CPU per world, statics and rows).
CLEAR_CAP = 1.3


class WorldStatics(NamedTuple):
    """What the rows read of one world besides the flight (module docstring)."""

    mesh: Mesh
    opts: Strict
    bvh: Bvh
    #: (V, n_img) bool, lit at each image (``(V, 0)`` when the options read no light).
    lit: np.ndarray
    #: (V,) float64, the cosine of each vertex's clear cone (2.0: none; all 2.0 without
    #: occlusion).
    cos_clear: np.ndarray


def needs_light(options: CoverageOptions) -> bool:
    """The rows read the lighting: illumination is a filter, or the requirement asks
    for light."""
    return bool(options.illumination or (options.requirement and options.require_lit))


def world_statics(shape, options: CoverageOptions, sun_T, n_img: int) -> WorldStatics:
    """The :class:`WorldStatics` of ``shape`` (a :class:`~ideas_hpc.body.shape.Shape`) under
    the unit body -> Sun directions ``sun_T`` ((n_img, 3), or None when the options read
    no Sun) at ``n_img`` images, for the coverage ``options``."""
    opts, bvh = strict_records(shape, options, sun_T, int(n_img))
    mesh = mesh_record(shape)
    nv = mesh.vertices_T_m.shape[0]
    if needs_light(options):
        lit = _ws.lit_at_images(mesh, opts.sun_T, bvh)
    else:
        lit = np.zeros((nv, 0), dtype=np.bool_)
    cos_clear = _ws.clear_cones(mesh, bvh, CLEAR_CAP) if options.occlusion else np.full(nv, 2.0)
    return WorldStatics(mesh, opts, bvh, lit, cos_clear)


def rows_of_world(statics: WorldStatics, options: CoverageOptions, r_img, dcm,
                  image_times, frustum, device: str = "cpu") -> np.ndarray:
    """(K, V) bool rows (seen, or mapped with a requirement) of candidates flown through
    the world of ``statics`` (module docstring): positions ``r_img`` (K, n_img, 3) m and
    camera DCMs ``dcm`` (K, n_img, 3, 3) at ``image_times`` (s), with the camera's
    ``frustum`` ``(eta_rad, near_m, far_m)``; mapped rows on ``device`` (``"cpu"`` or
    ``"cuda"``: an :class:`~ideas_hpc.base.errors.InputError` naming ``device`` where
    ``numba.cuda`` has none)."""
    check_device(device, "device")
    eta, near, far = frustum
    mesh, opts, bvh, lit, cos_clear = statics
    # the shape is only read for its name in messages: the records hold the mesh
    r, c, tan_eta, near, far, _ = check_geometry(None, r_img, dcm, eta, near, far)
    t = np.ascontiguousarray(np.asarray(image_times, dtype=np.float64))
    cam = camera_record(r, c, t, tan_eta, near, far, options.mode == "exact")
    if not options.requirement:
        return observed_by_spacecraft(mesh, cam, opts, bvh)
    quality = quality_record(options)
    if options.require_stereo:
        usable, stereo, _ = quality_by_spacecraft(mesh, cam, opts, bvh, quality)
        return usable & stereo
    kernel = _wr.mapped_by_spacecraft
    if device == "cuda":
        from ideas_hpc.core.mapping.world_rows_cuda import mapped_by_spacecraft_cuda as kernel
    return kernel(mesh, cam, opts, bvh, QualityTests(*quality_tests(quality)), lit, cos_clear)
