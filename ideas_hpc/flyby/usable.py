"""Usable images (SPEC section 7d): an image observes only when it is sharp and settled.

An image at time ``t`` is usable when

* its smear is at most ``k_smear`` pixels: ``|omega_img x u| t_exp <= k_smear IFOV``,
  with the instantaneous field of view ``IFOV = 2 eta / n_pix`` for a detector of
  ``n_pix`` pixels across, ``pitch / focal length`` for a detector given by its
  pitch, or the diffraction sample ``lambda / D`` otherwise. ``omega_img =
  omega_CN - omega_LOS`` is the motion of the scene's image on the detector: the
  camera's inertial rate relative to the turning line of sight ``u`` to the
  imaged point P, ``omega_LOS = (u x v_rel) / rho`` (SPEC 7d, corrected; the
  derivation and the kernel are :mod:`ideas_hpc.core.attitude.smear`). In the
  camera frame C (boresight ``z_C``) with the spacecraft's velocity ``v``
  relative to the body frame T and the body's spin ``omega_TN``:
  ``|omega_img x z_C| = sqrt((w_x - wT_x - v_y / rho)^2 + (w_y - wT_y + v_x / rho)^2)``.
  It is 0 for a camera that follows the line of sight to P and ``|v_perp| / rho``
  for one fixed in inertial space over a still body. (Before issue 42 the test
  read the camera's inertial rate ``|omega_CN|``, which calls a camera that
  tracks the body at 10 km/s smeared and an inertially fixed one sharp.)
* the pointing has settled: the principal angle of the attitude error
  ``sigma_B/R`` is at most ``settle_rad``.

Approximation, stated: the smear is evaluated at the footprint centre only, the
point P where the boresight meets the sphere of the body's volume-equivalent
mean radius about its centre (:func:`scene_radius_m`); when the boresight misses
that sphere, ``rho`` is the range of its limb, ``sqrt(|r|^2 - R^2)`` (equal to the
hit range at grazing, so continuous). Points off the centre also move by the roll
about the boresight and sit at other ranges; the real surface lies between
``R_min`` and ``R_max``, so at a given pointing the centre's smear scales by
``rho(R) / rho(surface)``. On the paper's geometry (0.1 km/s past Eros at
``d_sep`` = 155.9 km, 10 ms, IFOV 6.875 microrad) the footprint centre smears
by ``v t_exp / (rho IFOV)`` = 0.92-0.93 pixel away from closest approach and 0.99
pixel at it (``rho`` = 147.5 km): the paper's camera is sized so that ``v t_exp``
(1 m) is its ground sample at the altitude ``h`` = 145.5 km, so a point at
``R_av`` (10.4 km) is smeared by exactly one pixel.

The closed loop (``attitude.mode = "simulated"``) is tested at its own rate and
error. Perfect tracking (``attitude.mode = "ideal"``) faces the smear test too, where
its geometry says so (:attr:`~ideas_hpc.flyby.geometry.Geometry.ideal_images_tested`:
an encounter): its camera turns at its reference's rate, ``omega_CN = [C B]
omega_RN``, the reference's analytic rate at each image
(:func:`ideas_hpc.flyby.camera.ideal_omega_BN_B_at`: body tracking's from the flown
position and velocity, toward the predicted target before terminal tracking locks and
turned by the centroid error after; the ring frames' ``reference_rates``, zero for an
encounter's swarm-frame Nadir Pointing, which is fixed in inertial space), fed to the
same kernel and the same flags (:func:`ideas_hpc.flyby.camera.ideal_usable`); its
attitude error is zero, so there is no settle test. At 10 km/s an inertially fixed
camera smears by ``v t_exp / (rho IFOV)`` pixels (2.5 to 10 in an encounter's 1 ms)
and loses its images, while body tracking smears the footprint centre by its parallax
only (``tests/test_smear.py``). The paper's geometry keeps the paper's ideal mode and
counts every image: its Nadir Pointing turns with the body, so the smear above
(0.92-0.99 pixel) would keep every image anyway, but its FoV sweeps (Fig. 32) turn
at up to 17 pixels per exposure, which the paper's 100 % does not discount.
An unusable image is
replaced by a *blind* camera, one whose boresight points from the body centre
through the spacecraft, away from the body: with the spacecraft outside the
body's bounding sphere (``|r| > r_max``) every vertex then lies behind it
(``q_z = z . (p - r) <= r_max - |r| < 0``); inside the sphere but outside the
body's convex hull it points along the normal of a plane that separates the two
(:func:`separating_axis`), with the same effect. So it observes nothing in every
coverage mode, and every consumer of the camera DCMs (the coverage kernels and
the scenario rows' proofs alike) sees the same images.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.body.mass_properties import mean_radius

#: Defaults (docs/attitude-start.md): a 10 ms exposure, one pixel of smear, 0.1 deg settled.
#: 10 ms is the paper's pass (0.1 km/s): its camera is sized so that ``v t_exp`` is one
#: ground sample.
EXPOSURE_MS = 10.0
#: The default exposure on an encounter (``flyby.geometry = "encounter"``), ms. A framing
#: camera at a fast flyby exposes for milliseconds: tracking the body centre at 10 km/s and
#: ~157 km, the footprint centre (at the mean radius ``R``) moves across it by the parallax
#: ``v (1 / (rho - R) - 1 / rho)`` = 3.4e-3 rad/s, 5 pixels of the paper's 6.9 microrad
#: camera in 10 ms and 0.5 in 1 ms (1.1 at Eros' 17 km long axis). New Horizons' LORRI sets
#: its exposure in 1 ms steps (0 to 64 967 ms; Weaver et al. 2020, PASP 132, 035003) and
#: imaged Pluto near closest approach with "unusually short exposures to avoid blurring"
#: (NASA/JHUAPL, December 2015 release of the closest-approach strip).
ENCOUNTER_EXPOSURE_MS = 1.0
SMEAR_PIXELS = 1.0
SETTLE_DEG = 0.1
EXPOSURE_S = EXPOSURE_MS * 1e-3
SETTLE_RAD = math.radians(SETTLE_DEG)


@dataclass(frozen=True)
class ImageUse:
    """The usable-image test, SI: IFOV (rad), exposure (s), smear limit (pixels),
    settle limit (rad)."""

    ifov_rad: float
    exposure_s: float = EXPOSURE_S
    smear_pixels: float = SMEAR_PIXELS
    settle_rad: float = SETTLE_RAD

    def __post_init__(self):
        for name in ("ifov_rad", "exposure_s", "smear_pixels", "settle_rad"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise InputError(f"must be a finite number > 0, got {v!r}", field=name)

    @property
    def max_rate_rad_s(self) -> float:
        """Largest image rate across the line of sight of a usable image, rad/s."""
        return self.smear_pixels * self.ifov_rad / self.exposure_s

    def smear_pixels_of(self, rate_rad_s):
        """Smear in pixels of image rates ``rate_rad_s`` (rad/s): ``rate t_exp / IFOV``."""
        return np.asarray(rate_rad_s) * self.exposure_s / self.ifov_rad


def default_exposure_s(encounter: bool) -> float:
    """The exposure (s) when ``instrument.exposure_ms`` is not given: 1 ms on an encounter
    (:data:`ENCOUNTER_EXPOSURE_MS`), 10 ms on the paper's pass (:data:`EXPOSURE_MS`)."""
    return (ENCOUNTER_EXPOSURE_MS if encounter else EXPOSURE_MS) * 1e-3


def scene_radius_m(shape) -> float:
    """Radius (m) of the sphere on which the smear test places the footprint centre: the
    body's volume-equivalent mean radius ``(3 V / 4 pi)^(1/3)`` (8.41 km for eros001708;
    its ``R_av = (R_max + R_min) / 2`` is 10.43 km, ``R_max`` 17.65 km)."""
    return float(mean_radius(float(shape.volume)))


def ifov_rad(eta_rad: float, *, pixels_across=None, pixel_pitch_m=None, focal_length_m=None,
             wavelength_m=None, aperture_m=None) -> float:
    """Instantaneous field of view, rad: ``2 eta / n_pix`` with a pixel count, else
    ``pitch / focal length`` with a detector, else ``lambda / D``."""
    if pixels_across is not None:
        return 2.0 * float(eta_rad) / float(pixels_across)
    if pixel_pitch_m is not None and focal_length_m is not None:
        return float(pixel_pitch_m) / float(focal_length_m)
    if wavelength_m is None or aperture_m is None:
        raise InputError("needs a pixel count, a detector (pitch and focal length) or the "
                         "wavelength and aperture", field="ifov_rad")
    return float(wavelength_m) / float(aperture_m)


def usable_images(use: ImageUse, rate_rad_s: np.ndarray, error_rad: np.ndarray):
    """``(usable (N, n_img) bool, smeared (N,) int32, unsettled (N,) int32)``.

    ``rate_rad_s`` and ``error_rad`` (N, n_img): the footprint centre's image rate
    across the line of sight (:mod:`ideas_hpc.core.attitude.smear`) and the attitude
    error angle at the images. An image may fail both tests; it then counts in both.
    """
    smeared = np.asarray(rate_rad_s) * use.exposure_s > use.smear_pixels * use.ifov_rad
    unsettled = np.asarray(error_rad) > use.settle_rad
    return (~(smeared | unsettled), smeared.sum(axis=1).astype(np.int32),
            unsettled.sum(axis=1).astype(np.int32))


def blind(dcm_BT: np.ndarray, r_img_T: np.ndarray, usable: np.ndarray,
          r_max_m: float, vertices_T: np.ndarray | None = None) -> np.ndarray:
    """Camera DCMs (N, n_img, 3, 3) with every unusable image blinded (module docstring)."""
    out = np.array(dcm_BT, dtype=np.float64, copy=True)
    blind_into(out, r_img_T, usable, r_max_m, vertices_T)
    return np.ascontiguousarray(out)


def separating_axis(r_T: np.ndarray, vertices_T: np.ndarray) -> np.ndarray | None:
    """A camera axis ``z`` with every vertex ``p`` behind it, ``dot(z, p - r) < 0``, or None.

    For a spacecraft inside the bounding sphere the radial direction may see part of an
    elongated body (Eros' waist is 5.5 km from its centre, its ends 17.6 km). Any
    plane that separates ``r`` from the body's convex hull gives such a ``z`` (its normal
    toward ``r``). It is the linear programme ``max t`` subject to
    ``z . (p_i - r) + t <= 0`` and ``-1 <= z_k <= 1`` (HiGHS): ``t > 0`` at the optimum
    exactly when ``r`` lies outside the hull; inside it (an impact) there is none."""
    from scipy.optimize import linprog

    d = np.asarray(vertices_T, dtype=np.float64) - np.asarray(r_T, dtype=np.float64)
    scale = float(np.max(np.abs(d))) or 1.0
    a = np.hstack([d / scale, np.ones((d.shape[0], 1))])
    res = linprog(np.array([0.0, 0.0, 0.0, -1.0]), A_ub=a, b_ub=np.zeros(d.shape[0]),
                  bounds=[(-1.0, 1.0)] * 3 + [(0.0, None)], method="highs")
    if res.status != 0 or res.x[3] <= 0.0:
        return None
    z = res.x[:3] / np.linalg.norm(res.x[:3])
    return z if np.max(d @ z) < 0.0 else None          # checked, not trusted to tolerance


def _frames(z: np.ndarray) -> np.ndarray:
    """Rows ``x, y, z`` (M, 3, 3) of right-handed frames with the given unit ``z`` (M, 3)."""
    # any x orthogonal to z: the axis of z's smallest component crossed with z
    e = np.zeros_like(z)
    e[np.arange(z.shape[0]), np.argmin(np.abs(z), axis=1)] = 1.0
    x = np.cross(e, z)
    x /= np.linalg.norm(x, axis=1)[:, None]
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=1)


def blind_into(dcm_BT: np.ndarray, r_img_T: np.ndarray, usable: np.ndarray,
               r_max_m: float, vertices_T: np.ndarray | None = None) -> None:
    """:func:`blind` in place on ``dcm_BT`` (float64, N x n_img x 3 x 3): the scenario
    bank blinds its reused buffer without a copy.

    Outside the bounding sphere (radius ``r_max_m``) the camera looks radially outward.
    Inside it, with ``vertices_T`` given, it looks along :func:`separating_axis` (a large
    navigation error can bring a spacecraft past an elongated body's waist inside the
    sphere: ``ideas-hpc study`` at a 100 km navigation sigma, 2026-12-07); where none
    exists (the spacecraft inside the body's hull) or without vertices the image cannot
    be blinded and the error names it."""
    bad = ~np.asarray(usable, dtype=bool)
    if not bad.any():
        return
    r = np.asarray(r_img_T, dtype=np.float64)[bad]
    dist = np.linalg.norm(r, axis=1)
    z = r / np.maximum(dist, 1e-300)[:, None]
    for k in np.flatnonzero(~(dist > r_max_m)):
        axis = None if vertices_T is None else separating_axis(r[k], vertices_T)
        if axis is None:
            where = ("inside the body's convex hull" if vertices_T is not None else
                     f"inside its bounding sphere ({r_max_m / 1e3:.3g} km)")
            raise InputError(f"an unusable image is taken {dist[k] / 1e3:.3g} km from the body "
                             f"centre, {where}: it cannot be blinded", field="r_img_T")
        z[k] = axis
    dcm_BT[bad] = _frames(z)     # rows: the camera axes in T
