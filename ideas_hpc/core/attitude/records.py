"""Records the attitude kernels take (issue 21 item 4).

Named tuples of (3,) float64 arrays and float64 scalars, passed to compiled code
as one tuple each (see :mod:`ideas_hpc.core.mapping.records`). The boundary
(:mod:`ideas_hpc.attitude.simulate`) builds them once with exactly these types.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class ControlGains(NamedTuple):
    """Sliding-mode controller gains (``core.control``, SPEC section 5)."""

    #: (3,) float64, ``K_P``, 1/s.
    k_p: np.ndarray
    #: (3,) float64, ``K_I``, 1/s^2.
    k_i: np.ndarray
    #: (3,) float64, reaching gain, rad/s^2.
    eta: np.ndarray
    #: (3,) float64, boundary-layer slope, s/rad (already capped for the step).
    phi: np.ndarray
    #: The MRP error integral only accumulates while ``|ds| < int_limit`` (``inf``: always).
    int_limit: float


class Wheels(NamedTuple):
    """The spacecraft's inertias and reaction-wheel limits."""

    #: (3,) float64, ``[I_RW]`` principal moments, kg m^2.
    I_rw_kgm2: np.ndarray
    #: (3,) float64, wheel spin inertias, kg m^2.
    J_s_kgm2: np.ndarray
    #: Torque limit, N m.
    u_max_Nm: float
    #: Wheel momentum limit, N m s.
    h_max_Nms: float


class Ring(NamedTuple):
    """One spacecraft's attitude reference (``core.maneuvers.reference_into``)."""

    #: 0 Nadir Pointing, 1 FoV Sweeping.
    mode: int
    #: (3,) float64, MRP of the ring frame ``[R T]``.
    sigma_RT: np.ndarray
    #: (3, 3) float64, ring frame DCM ``[R T]``.
    dcm_RT: np.ndarray
    #: Target spin rate, rad/s.
    spin_rate: float
    #: FoV sweep amplitude, rad.
    theta_max: float
    #: FoV sweep period, s.
    period_s: float


class Initial(NamedTuple):
    """Initial states of ``S x N`` spacecraft."""

    #: (S, N, 3) float64, ``sigma_BN`` (MRP).
    sigma_BN: np.ndarray
    #: (S, N, 3) float64, ``omega_BN_B``, rad/s.
    omega_BN_B: np.ndarray
    #: (S, N, 3) float64, wheel speeds, rad/s.
    wheel_rad_s: np.ndarray


class StepTables(NamedTuple):
    """What :func:`~ideas_hpc.core.attitude.batch.simulate_batch` reads at every step
    ``k`` (``t = k dt``) of spacecraft ``i``; a table with no steps (``(N, 0, .)``)
    is not read."""

    #: (N, n_steps + 1, 9) float64, body tracking's reference ``[sigma_RN,
    #: omega_RN_R, omegadot_RN_R]`` (``core.maneuvers.track_reference_table``).
    reference: np.ndarray
    #: (N, n_steps + 1, 3) float64, the external (disturbance) torque in B, N m,
    #: held over the step (the sum of :mod:`ideas_hpc.attitude.torque_terms`).
    torque_B_N_m: np.ndarray


class ImageViews(NamedTuple):
    """What the scenario bank's one-pass flights
    (:mod:`~ideas_hpc.core.attitude.camera_batch`, :mod:`~ideas_hpc.core.attitude.camera_lanes`)
    read and write at the images of ``N`` spacecraft."""

    #: Image every ``img_every``-th step (``k = 0, img_every, ...``).
    img_every: int
    #: (n_img, 2) float64, ``cos, sin`` of the spin angle at the images
    #: (:func:`~ideas_hpc.core.attitude.camera_batch.spin_table`).
    cs_img: np.ndarray
    #: (N, 3, 3) float64, camera misalignments ``[C B]``; ``(0, 3, 3)``: none.
    dcm_CB: np.ndarray
    #: (3,) float64, ``(exposure s, smear limit rad = pixels x IFOV, settle limit
    #: rad)``: an image is usable unless ``rate * exposure > smear limit`` or
    #: ``error > settle``, ``rate`` the footprint centre's image rate
    #: (:func:`~ideas_hpc.core.attitude.smear.smear_rate_s`).
    use: np.ndarray
    #: (N, n_img, 3) float64, the spacecraft's positions at the images, m, T.
    r_T: np.ndarray
    #: (N, n_img, 3) float64, its velocities relative to T at the images, m/s;
    #: ``(0, 0, 3)``: no smear test (every rate reads 0).
    v_T: np.ndarray
    #: Radius of the sphere the footprint centre lies on, m
    #: (:func:`~ideas_hpc.core.attitude.smear.scene_range_s`).
    radius_m: float
    #: (N, n_img, 3, 3) float64, receives ``[C T]`` at every image.
    dcm_CT_out: np.ndarray
    #: (N, n_img) bool, receives the usable-image flags.
    usable_out: np.ndarray



class SwarmReference(NamedTuple):
    """The references of ``N`` spacecraft for the CUDA kernel
    (:mod:`~ideas_hpc.core.attitude.batch_cuda`): the arrays of :class:`Ring`, one row
    per spacecraft."""

    #: Maneuver code (``core.attitude.maneuvers``).
    mode: int
    #: (N, 3, 3) float64, ring frames ``[R_i T]``.
    dcm_RT: np.ndarray
    #: (N, 3) float64, their MRPs.
    sigma_RT: np.ndarray
    #: Target spin rate, rad/s.
    spin_rate: float
    #: (N,) float64, FoV sweep periods, s.
    periods_s: np.ndarray
    #: FoV sweep amplitude, rad.
    theta_max: float


class LoopSteps(NamedTuple):
    """The closed loop's steps: ``dt_s`` (s), ``n_steps``, a record every ``decimate``-th
    step and an image every ``img_every``-th; ``disturbed``: the torque table is read."""

    dt_s: float
    n_steps: int
    decimate: int
    img_every: int
    disturbed: bool


class Recorded(NamedTuple):
    """What the CUDA kernel writes for ``S x N`` jobs (``R`` records, ``n_img`` images):
    the outputs of :func:`~ideas_hpc.core.attitude.batch.simulate_batch`, units as there."""

    #: (S, N, R, 3) ``sigma_B/R``.
    sigma_error: np.ndarray
    #: (S, N, R, 3) ``omega_B/R`` in B, rad/s.
    omega_error: np.ndarray
    #: (S, N, R, 3) wheel speeds, rad/s.
    wheel_speed: np.ndarray
    #: (S, N, R, 3) wheel torques, N m.
    wheel_torque: np.ndarray
    #: (S, N, n_img, 3, 3) camera ``[B T]`` at the images.
    dcm_BT: np.ndarray
    #: (S, N, n_img, 3) ``omega_BN`` in B at the images, rad/s.
    image_omega: np.ndarray
    #: (S, N, n_img) attitude error angle at the images, rad.
    image_error: np.ndarray
    #: (S, N) largest ``|u|``, N m.
    max_torque: np.ndarray
    #: (S, N) largest wheel momentum, N m s.
    max_momentum: np.ndarray
