"""Initial conditions, ideal camera attitude and the batched closed-loop simulation
(SPEC section 5). Orchestration only: the physics is in ``core.attitude``,
``core.maneuvers``, ``core.control`` and ``core.attitude_batch``."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ideas_hpc.attitude.device import batch_kernel
from ideas_hpc.core.attitude.records import ControlGains, Initial, StepTables, Wheels
from ideas_hpc.core.dynamics.frames import dcm_RT as _dcm_RT
from ideas_hpc.core.attitude.maneuvers import TRACK_MODE, reference_dcm_BT, reference_rates
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.seeds import sample_rng
from ideas_hpc.base.units import RPM
from ideas_hpc.attitude.checks import check_theta, init_array, steps
from ideas_hpc.base.fields import number
from ideas_hpc.attitude.gains import gains_from_config
from ideas_hpc.attitude.maneuvers import P_MIN_DEFAULT, maneuver_args
from ideas_hpc.attitude.spacecraft import default_spacecraft, validate_spacecraft
from ideas_hpc.attitude.torque_terms import pack_torques
from ideas_hpc.attitude.start import absolute_start, reference_state0
from ideas_hpc.attitude.run_settings import (AttitudeModel, AttitudeRun, InitialState, Pointing,
                                             from_keywords)


def initial_conditions(seed: int, sample: int, n_spacecraft: int):
    """Random initial attitude state of one Monte Carlo sample (SPEC section 5).

    Drawn from the sample's own stream (:func:`ideas_hpc.base.seeds.sample_rng`,
    ``SeedSequence(seed, spawn_key=(sample,))``) in this order: sigma (N, 3) uniform in [-1, 1]
    then shadow-switched when ``|sigma| > 1``; omega (N, 3) uniform in
    [-1, 1] rpm; wheel speeds (N, 3) uniform in [-10, 10] rpm.

    Returns
    -------
    sigma_BN0 : (N, 3) float64
    omega_BN0_B : (N, 3) float64, rad/s
    wheel_speed0 : (N, 3) float64, rad/s
    """
    return draw_initial_conditions(sample_rng(seed, sample), n_spacecraft)


def draw_initial_conditions(rng: np.random.Generator, n_spacecraft: int):
    """The draws of :func:`initial_conditions` from generator ``rng`` (same order and laws)."""
    n = int(n_spacecraft)
    sigma = rng.uniform(-1.0, 1.0, (n, 3))
    omega = rng.uniform(-1.0, 1.0, (n, 3)) * RPM
    wheel = rng.uniform(-10.0, 10.0, (n, 3)) * RPM
    s2 = np.einsum("ij,ij->i", sigma, sigma)
    big = s2 > 1.0
    sigma[big] = -sigma[big] / s2[big, None]
    return sigma, omega, wheel


@dataclass
class AttitudeResult:
    """Output of :func:`simulate_attitude` (store variables of SPEC section 9).

    Attributes
    ----------
    times : (T,) s
    sigma_error : (S, N, T, 3) ``sigma_B/R`` (MRP)
    omega_error : (S, N, T, 3) ``omega_B/R`` in B, rad/s
    wheel_speed : (S, N, T, 3) rad/s
    wheel_torque : (S, N, T, 3) N m (held from each time on)
    image_times : (n_img,) s
    dcm_BT : (S, N, n_img, 3, 3) camera DCM, body <- target frame
    max_torque : (S, N) max ``|u_s|`` over the run, N m
    max_momentum : (S, N) max ``|J_s Omega|`` over the run, N m s
    image_rate : (S, N, n_img) ``|omega_BN|`` at the images, rad/s (the camera's
        inertial rate; not the smear rate, which needs the trajectory)
    image_omega : (S, N, n_img, 3) ``omega_BN`` in B at the images, rad/s
    image_error : (S, N, n_img) principal angle of ``sigma_B/R`` at the images, rad
    image_smear_rate : (S, N, n_img) or None
        The footprint centre's image rate across the line of sight at the images,
        rad/s (SPEC 7d, :mod:`ideas_hpc.core.attitude.smear`): set by the flyby, which
        knows the trajectory and the camera misalignment
        (:func:`ideas_hpc.flyby.camera.smear_rates_of`); None here.
    """

    times: np.ndarray
    sigma_error: np.ndarray
    omega_error: np.ndarray
    wheel_speed: np.ndarray
    wheel_torque: np.ndarray
    image_times: np.ndarray
    dcm_BT: np.ndarray
    max_torque: np.ndarray
    max_momentum: np.ndarray
    attrs: dict = field(default_factory=dict)
    image_rate: np.ndarray | None = None
    image_error: np.ndarray | None = None
    image_omega: np.ndarray | None = None
    image_smear_rate: np.ndarray | None = None

    def to_dataset(self):
        """``xarray.Dataset`` with the SPEC section 9 names and dims."""
        import xarray as xr

        d4 = ("sample", "spacecraft", "time", "axis")
        w4 = ("sample", "spacecraft", "time", "wheel")
        return xr.Dataset(
            {
                "sigma_error": (d4, self.sigma_error, {"units": "1", "long_name": "MRP sigma_B/R"}),
                "omega_error": (d4, self.omega_error, {"units": "rad/s"}),
                "wheel_speed": (w4, self.wheel_speed, {"units": "rad/s"}),
                "wheel_torque": (w4, self.wheel_torque, {"units": "N m"}),
                "dcm_BT": (("sample", "spacecraft", "image_time", "row", "col"), self.dcm_BT,
                           {"units": "1"}),
                "max_torque": (("sample", "spacecraft"), self.max_torque, {"units": "N m"}),
                "max_momentum": (("sample", "spacecraft"), self.max_momentum,
                                 {"units": "N m s"}),
            },
            coords={"time": ("time", self.times, {"units": "s"}),
                    "image_time": ("image_time", self.image_times, {"units": "s"}),
                    "axis": ["x", "y", "z"], "wheel": [0, 1, 2]},
            attrs=dict(self.attrs),
        )


def _ring_dcms(theta, dcm_TS):
    ts = np.eye(3) if dcm_TS is None else np.ascontiguousarray(dcm_TS, dtype=np.float64)
    if ts.shape != (3, 3) or not np.allclose(ts @ ts.T, np.eye(3), atol=1e-9) \
            or np.linalg.det(ts) <= 0:
        raise InputError("must be a proper rotation matrix (3, 3)", field="dcm_TS")
    return np.ascontiguousarray(np.array([_dcm_RT(float(t), ts) for t in theta]).reshape(-1, 3, 3))


def _ref_table(ref_table, n: int, n_steps: int) -> np.ndarray:
    if ref_table is None:
        return np.empty((n, 0, 9))
    t = np.ascontiguousarray(ref_table, dtype=np.float64)
    if t.shape != (n, n_steps + 1, 9) or not np.all(np.isfinite(t)):
        raise InputError(f"must be finite with shape ({n}, {n_steps + 1}, 9), got {t.shape}",
                         field="ref_table")
    return t


def ideal_dcm_BT(theta, spin_rate, image_times, *, mode="np", periods=None,
                 theta_max=None, dcm_TS=None, p_min=P_MIN_DEFAULT):
    """Camera DCM ``[B T]`` under perfect tracking (B = reference frame).

    Parameters
    ----------
    theta : (N,) rad
        Swarm angles.
    spin_rate : float
        rad/s (unused: with B fixed to R_i, which is fixed in T, ``[BT]`` does
        not depend on the spin; kept for a uniform signature).
    image_times : (n_img,) s
    mode : str
        A maneuver of :data:`~ideas_hpc.attitude.maneuvers.MANEUVERS` ('np', 'fov').
    periods : (N,) s, for 'fov'
    theta_max : rad, for 'fov' (default 1.9138 deg)
    dcm_TS : (3, 3), default identity

    Returns
    -------
    (N, n_img, 3, 3) float64
    """
    th = check_theta(theta)
    man, p, tm = maneuver_args(mode, th.size, periods, theta_max, p_min)
    times = np.ascontiguousarray(np.atleast_1d(np.asarray(image_times, dtype=np.float64)))
    if times.ndim != 1 or not np.all(np.isfinite(times)):
        raise InputError("must be a 1-D array of finite times in s", field="image_times")
    return reference_dcm_BT(man.code, _ring_dcms(th, dcm_TS), tm, p, times)


def ideal_omega_BN_B(theta, spin_rate, image_times, *, mode="np", periods=None,
                     theta_max=None, dcm_TS=None, p_min=P_MIN_DEFAULT) -> np.ndarray:
    """Inertial rate ``omega_BN`` (B components, rad/s) under perfect tracking at the
    image times (s since t0): the reference's ``omega_RN_R`` (B = the reference frame),
    with the spin ``spin_rate`` (rad/s) of the ring frames about ``z_T``. Arguments as
    :func:`ideal_dcm_BT`; not for body tracking (its reference is a table, not a
    function of time). Returns (N, n_img, 3)."""
    th = check_theta(theta)
    man, p, tm = maneuver_args(mode, th.size, periods, theta_max, p_min)
    if man.code == TRACK_MODE:
        raise InputError("body tracking has no reference function of time", field="mode")
    times = np.ascontiguousarray(np.atleast_1d(np.asarray(image_times, dtype=np.float64)))
    return reference_rates(man.code, _ring_dcms(th, dcm_TS), float(spin_rate), float(tm),
                           np.ascontiguousarray(p, dtype=np.float64), times)


def simulate_attitude(theta, spin_rate, t_f=None, *, run: AttitudeRun | None = None,
                      pointing: Pointing | None = None, model: AttitudeModel | None = None,
                      state0: InitialState | None = None, device: str = "cpu",
                      **keywords) -> AttitudeResult:
    """Closed-loop attitude of ``S`` samples of an ``N``-spacecraft swarm (SPEC section 5).

    The settings travel in four records (:mod:`ideas_hpc.attitude.run_settings`):
    ``run`` (:class:`AttitudeRun`: ``t_f_s``, ``dt_s``, ``image_dt_s``, ``decimate``,
    ``seed``, ``n_samples``, ``start``, ``acquisition_s``), ``pointing``
    (:class:`Pointing`: ``mode``, ``periods_s``, ``theta_max_rad``, ``p_min_s``,
    ``dcm_TS``, ``ref_table``), ``model`` (:class:`AttitudeModel`: ``gains``,
    ``spacecraft``, ``torques``) and ``state0`` (:class:`InitialState`). The older
    keywords below (``dt=``, ``mode=``, ``sigma0=``...) fill the same fields, and
    the errors name them.

    Parameters
    ----------
    theta : (N,) rad
        Swarm angles (ring frames from ``core.frames.dcm_RT``).
    spin_rate : float
        Target spin rate about +z_T, rad/s.
    t_f : float
        Duration, s (a multiple of ``dt``).
    mode : str
        A maneuver of :data:`~ideas_hpc.attitude.maneuvers.MANEUVERS`: 'np'
        (Nadir Pointing) or 'fov' (FoV Sweeping).
    periods : (N,) s
        Sweep periods for 'fov' (>= ``p_min``).
    theta_max : float
        Sweep amplitude, rad (default 1.9138 deg).
    gains : Gains, preset name, or config table
        Default: the preset of ``mode`` (Table 5 / Table 6).
    spacecraft : SpacecraftModel
        Default :func:`default_spacecraft`.
    dt : float
        Integration and control step, s; must divide ``image_dt``.
    image_dt : float
        Image period, s (0.2: 5 images/s).
    sigma0, omega0, wheel0 : (S, N, 3) or (N, 3)
        Initial ``sigma_BN``, ``omega_BN_B`` (rad/s) and wheel speeds (rad/s).
        When ``sigma0`` is None all three are drawn by
        :func:`initial_conditions` for samples ``0 .. n_samples - 1`` of ``seed``.
    decimate : int
        Keep every ``decimate``-th step in the time series.
    dcm_TS : (3, 3)
        Swarm frame ``[TS]`` (default identity).
    p_min : float
        Minimum sweep period, s (paper: 0.3 min).
    ref_table : (N, n_steps + 1, 9), optional
        Body tracking ('track'): the reference at every step
        (:func:`ideas_hpc.core.attitude.maneuvers.track_reference_table`); its frame
        is inertial, so give ``spin_rate`` 0 and read ``dcm_BT`` as ``[B N]``.
    torques : sequence of torque terms
        Disturbance torques (:mod:`ideas_hpc.attitude.torque_terms`), summed
        and held over each step; the controller is not told them.
    start : {'absolute', 'reference'}
        'reference': ``sigma0``, ``omega0`` are the errors ``sigma_B/R`` and
        ``omega_B/R`` (B components) about the reference at t = 0 of the geometry
        flown (:mod:`ideas_hpc.attitude.start`); zeros start exactly on it.
    acquisition_s : float
        With ``start = 'absolute'`` and > 0: first fly the loop from the given
        state for this long (s, a multiple of ``dt``) on the reference's first
        frame and rate (Nadir Pointing for body tracking), then start the window
        from the attitude, rate and wheel errors reached (the controller's
        integral restarts at zero).
    device : {'cpu', 'cuda'}
        Where the closed loop runs (:mod:`ideas_hpc.attitude.device`); same outputs.

    Returns
    -------
    AttitudeResult
    """
    run, pointing, model, state0 = from_keywords(t_f, run, pointing, model, state0, keywords)
    t_f, dt, image_dt, decimate = run.t_f_s, run.dt_s, run.image_dt_s, run.decimate
    seed, n_samples, start, acquisition_s = run.seed, run.n_samples, run.start, run.acquisition_s
    mode, periods, theta_max = pointing.mode, pointing.periods_s, pointing.theta_max_rad
    p_min, dcm_TS, ref_table = pointing.p_min_s, pointing.dcm_TS, pointing.ref_table
    gains, spacecraft, torques = model.gains, model.spacecraft, model.torques
    sigma0, omega0, wheel0 = state0.arrays()
    th = check_theta(theta)
    n = th.size
    man, p, tm = maneuver_args(mode, n, periods, theta_max, p_min,
                               from_track=ref_table is not None)
    sc = validate_spacecraft(spacecraft or default_spacecraft())
    g = gains_from_config(man.gains if gains is None else gains)
    ws = float(spin_rate)
    if not math.isfinite(ws):
        raise InputError("must be finite (rad/s)", field="spin_rate")
    dt = number(dt, "dt", lo=0.0, lo_open=True)
    image_dt = number(image_dt, "image_dt", lo=0.0, lo_open=True)
    t_f = number(t_f, "t_f", lo=0.0, lo_open=True)
    n_steps = steps(t_f, dt, "t_f")
    img_every = steps(image_dt, dt, "image_dt")
    if isinstance(decimate, bool) or int(decimate) != decimate or decimate < 1:
        raise InputError(f"must be a positive integer, got {decimate!r}", field="decimate")
    decimate = int(decimate)
    if sigma0 is None:
        if omega0 is not None or wheel0 is not None:
            raise InputError("give sigma0, omega0 and wheel0 together", field="sigma0")
        draws = [initial_conditions(seed, k, n) for k in range(int(n_samples))]
        s0, w0, W0 = (np.ascontiguousarray(np.stack([d[j] for d in draws])) for j in range(3))
    else:
        if omega0 is None or wheel0 is None:
            raise InputError("give sigma0, omega0 and wheel0 together", field="omega0")
        s0 = init_array(sigma0, "sigma0", n)
        w0 = init_array(omega0, "omega0", n)
        W0 = init_array(wheel0, "wheel0", n)
        if not (s0.shape == w0.shape == W0.shape):
            raise InputError("sigma0, omega0, wheel0 must have the same shape", field="omega0")
    k_p, k_i, eta, phi = g.arrays(dt)
    table = _ref_table(ref_table, n, n_steps)
    tables = StepTables(table, pack_torques(tuple(torques), th, n_steps, dt, ws))
    rings = _ring_dcms(th, dcm_TS)
    gains_rec = ControlGains(k_p, k_i, eta, phi, float(g.int_limit))
    wheels = Wheels(sc.inertia_rw, sc.J_s, float(sc.u_max_N_m), float(sc.h_max_N_m_s))
    if start not in ("absolute", "reference"):
        raise InputError(f"must be 'absolute' or 'reference', got {start!r}", field="start")
    simulate_batch = batch_kernel(device)
    acq = float(acquisition_s)
    if not (math.isfinite(acq) and acq >= 0.0):
        raise InputError(f"must be finite and >= 0 s, got {acquisition_s!r}",
                         field="acquisition_s")
    if acq > 0.0:
        if start != "absolute":
            raise InputError("an acquisition starts from an absolute state",
                             field="acquisition_s")
        n_acq = steps(acq, dt, "acquisition_s")
        code = 0 if man.code == TRACK_MODE else man.code
        a = simulate_batch(code, rings, ws, p, tm, gains_rec, wheels, dt, n_acq, (n_acq, n_acq),
                           Initial(s0, w0, W0),
                           StepTables(np.empty((n, 0, 9)),
                                      pack_torques(tuple(torques), th, n_acq, dt, ws)))
        s0, w0, W0 = (np.ascontiguousarray(a[j][:, :, -1]) for j in range(3))
        start = "reference"
    if start == "reference":
        s_r, w_r = reference_state0(man.code, rings, ws, p, tm, table)
        s0, w0 = absolute_start(s_r, w_r, s0, w0)
    out = simulate_batch(man.code, rings, ws, p, tm, gains_rec, wheels,
                         dt, n_steps, (int(decimate), int(img_every)), Initial(s0, w0, W0), tables)
    sig, om, wh, tq, dcm, mu, mh, i_omega, i_err = out
    # the norm in the kernel's old order of operations: the smear test reads the same bits
    i_rate = np.sqrt(i_omega[..., 0] * i_omega[..., 0] + i_omega[..., 1] * i_omega[..., 1]
                     + i_omega[..., 2] * i_omega[..., 2])
    times = np.arange(0, n_steps + 1, decimate) * dt
    image_times = np.arange(0, n_steps + 1, img_every) * dt
    attrs = {"mode": mode, "dt": dt, "image_dt": image_dt, "spin_rate": ws,
             "theta_max": tm, "k_p": list(k_p), "k_i": list(k_i), "eta": list(eta),
             "phi_effective": list(phi), "int_limit": float(g.int_limit)}
    return AttitudeResult(times, sig, om, wh, tq, image_times, dcm, mu, mh, attrs,
                          image_rate=i_rate, image_error=i_err, image_omega=i_omega)
