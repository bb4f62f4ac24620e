"""Records the mapping kernels take and return (issue 21 item 4).

Plain named tuples of contiguous arrays and scalars: Numba passes them to
compiled code as one heterogeneous tuple (field access is free after
inlining, and ``cache=True`` works with them), so a kernel takes a handful of
records instead of twenty arrays. The boundary layer
(:mod:`ideas_hpc.mapping.coverage`) validates its inputs and builds them once
with the exact types below (float64 scalars as Python floats, flags as bools):
a field of another type compiles another specialisation.

Names carry frames and units: ``_T`` the body-fixed frame T, ``dcm_BT`` the
camera DCM B <- T, ``_m`` metres, ``_s`` seconds, ``_rad`` radians.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit


class Mesh(NamedTuple):
    """The shape model, frame T."""

    #: (V, 3) float64, vertex positions, m.
    vertices_T_m: np.ndarray
    #: (V, 3) float64, outward unit vertex normals.
    normals_T: np.ndarray
    #: (V,) float64, vertex areas (one third of the adjacent faces), m^2.
    areas_m2: np.ndarray


class Camera(NamedTuple):
    """The swarm's cameras at the images (SPEC section 6)."""

    #: (N, n_img, 3) float64, spacecraft positions in T per image, m.
    r_T_m: np.ndarray
    #: (N, n_img, 3, 3) float64, camera DCM (B <- T) per image; boresight +z_B.
    dcm_BT: np.ndarray
    #: (n_img,) float64, image times, s, non-decreasing.
    times_s: np.ndarray
    #: Tangent of the half angle of the square field of view.
    tan_eta: float
    #: Clipping distances along the boresight, m, ``0 < near_m < far_m``.
    near_m: float
    far_m: float
    #: Exact culling ``(r - p) . n > 0`` instead of the paper's ``r . n >= 0``.
    exact: bool


class Strict(NamedTuple):
    """The strict visibility options (SPEC section 6), off: ``(-2.0, inf, False, False, dummy)``."""

    #: Sine of the minimum elevation; ``-2.0`` disables the test.
    sin_min_elev: float
    #: Largest vertex-spacecraft range, m (``X D / lambda``); ``inf`` disables it.
    max_range_m: float
    #: Self-occlusion test.
    occlusion: bool
    #: Illumination test (lit and not shadowed).
    illumination: bool
    #: (n_img, 3) float64, unit body -> Sun direction in T per image ((1, 3) dummy
    #: when nothing reads it).
    sun_T: np.ndarray


class Bvh(NamedTuple):
    """BVH of the mesh faces (:func:`ideas_hpc.core.mapping.bvh.build_bvh`)."""

    #: (M, 6) float64, node boxes, m.
    node_bounds_m: np.ndarray
    #: (M, 4) int64, children and face range per node.
    node_info: np.ndarray
    #: (F, 9) float64, vertex a and edges b - a, c - a per face, m.
    tri_m: np.ndarray
    #: (F, 3) int64, vertex indices per face.
    tri_vid: np.ndarray


class Quality(NamedTuple):
    """What the quality pass asks of an observation (:mod:`ideas_hpc.core.mapping.quality`)."""

    #: Angular sample (lambda / D or pixel pitch / focal length), rad.
    rho_rad: float
    #: (6,) float64, ``[X_max (m), e_max, i_max, g_max, s_min, s_max (rad)]``.
    limits: np.ndarray
    #: A usable observation must be lit.
    require_lit: bool


class TimeTree(NamedTuple):
    """Time tree of the images (:func:`ideas_hpc.core.mapping.time_tree.time_tree`)."""

    #: (N, n_nodes, 24) float64, per-node reference camera and motion bounds.
    NF: np.ndarray
    #: (n_nodes, 4) int64, image range and children per node.
    NI: np.ndarray
    #: Secant of the half angle with a relative 1e-12 margin.
    sec_eta: float


class QualityTests(NamedTuple):
    """:class:`Quality` with the cosines of its angle limits (built in the kernel)."""

    rho_rad: float
    limits: np.ndarray
    require_lit: bool
    #: Some angle limit is set.
    check_ang: bool
    #: Cosines of the emission, incidence and phase limits (-2.0: not set).
    c_emi: float
    c_inc: float
    c_pha: float


class Sightings(NamedTuple):
    """What :func:`ideas_hpc.core.mapping.time_tree._scan` found for one (vertex, spacecraft)."""

    #: Images that saw the vertex (with ``early``: 0 or 1).
    count: int
    #: Earliest time seen so far, s (inf: never).
    first_s: float


class Observations(NamedTuple):
    """Running state of one vertex over the spacecraft, folded in by
    :func:`ideas_hpc.core.mapping.observations._scan` (which returns it updated)."""

    #: Usable unit lines of sight stored so far in the scratch ``U``.
    m: int
    #: Lit at some observation.
    lit: bool
    #: Observations so far.
    count: int
    #: Earliest observation time, s (inf: none).
    first_s: float
    #: Best effective ground sample, m, and its spacecraft and image (-1: none).
    best_res_m: float
    best_k: int
    best_i: int
    #: The last scanned spacecraft observed the vertex / had a usable observation.
    seen_k: bool
    usable_k: bool


class Nominal(NamedTuple):
    """What :func:`ideas_hpc.core.mapping.scenario_rows.perturbed_rows` knows of the
    nominal flight and the budget (:mod:`ideas_hpc.core.mapping.scenario_proofs`)."""

    #: (N, V) int, nominal image that sees the vertex most robustly (-1: none).
    witness: np.ndarray
    #: (N, V) float64, the witness's proof: camera-coordinate slack and position radius, m.
    slack_q_m: np.ndarray
    radius_m: np.ndarray
    #: (N, V, 2) int, first and last image a camera within the budget might see it at.
    window: np.ndarray
    #: (N, V) int, first image any attitude might see it at (positions within the budget).
    unseen_any: np.ndarray
    #: (N,) int64, written by ``perturbed_rows``: first image from which the deviation
    #: stays within the budget (-1: the flight is not near-rotations or not finite),
    #: and the same for the position deviation alone.
    i_ok: np.ndarray
    i_pos: np.ndarray
    #: (N, n_img, 3) and (N, n_img, 3, 3) float64, the nominal flight's positions (m)
    #: and camera DCMs at the images.
    r_nom_T_m: np.ndarray
    dcm_nom_BT: np.ndarray
    #: (3,) float64: the budget ``B_C`` (Frobenius) and ``B_r`` (m), and the largest
    #: ``||C C^T - I||_F`` of a flown DCM the proofs accept.
    budget: np.ndarray


@njit(cache=True, inline="always")
def no_observations(m, lit):
    """The state before any spacecraft: ``m`` directions already stored, ``lit``."""
    return Observations(m, lit, 0, np.inf, np.inf, -1, -1, False, False)
