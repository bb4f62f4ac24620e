"""Compiled orbit + STM propagator in the rotating body frame T (SPEC section 4).

Equations of motion (paper eqs. 3-5, SPEC section 4), frame T spinning at
``omega = [0, 0, w]`` about +z::

    r'' = -2 omega x r' - omega x (omega x r) + a_grav(r) + a_srp(t)
    Phi' = A Phi,   A = [[0, I], [G - W W, -2 W]],   W = [omega x]

The 42-element state is ``[r (3), v (3), Phi (36, row-major)]``; a 6-element
state propagates the trajectory alone.

Force model, packed for the kernels (built by the boundary layer,
:mod:`ideas_hpc.trajectory`):

``model`` (int)
    0 point mass; 1 point mass + degree 2 (C20, C22); 2 spherical harmonics
    (any degree); 3 constant-density polyhedron.
``consts`` (float64 array, see the ``K_*`` indices below)
    mu, c20, c22 (m^2), spin rate, SRP coefficient, G*rho, SH GM and
    reference radius, prime meridian, MU_SUN, heliocentric elements and pole.

Solar radiation pressure (cannonball, SPEC section 4)::

    a_srp = -(P_sun (1 AU / d)^2 C_r A / m) s_T(t)

with ``s_T`` the body->Sun unit vector in T (:mod:`ideas_hpc.core.ephemeris`).
``K_SRP`` holds ``P_sun AU^2 C_r A / m`` (m^3/s^2); 0 switches SRP off. SRP
does not depend on r, so it adds nothing to the gravity gradient.

Integrator: Dormand-Prince 8(5,3) ("DOP853", Hairer, Norsett & Wanner,
*Solving ODEs I*, section II.10) with the same step control, error norm
(RMS of the 5th and 3rd order embedded estimates over all components,
``scale = atol + rtol max(|y_old|, |y_new|)``), initial step choice and 7th
order dense output as ``scipy.integrate.solve_ivp(method="DOP853")``, so the
two agree to the tolerance. Samples on the output grid come from the dense
output.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .ephemeris import N_EPH, sun_T_fast
from .gravity import degree2, point_mass, polyhedron_gravity, sh_gravity

# indices into ``consts``
K_MU = 0
K_C20 = 1
K_C22 = 2
K_SPIN = 3
K_SRP = 4
K_GRHO = 5
K_SH_GM = 6
K_SH_RREF = 7
K_W0 = 8
K_MU_SUN = 9
K_ELEM = 10   # 6 values: a, e, i, RAAN, argp, nu0
K_POLE = 16   # 3 values: ra, dec, flag
K_EPH = 19    # N_EPH derived ephemeris constants (ephemeris_precompute)
N_CONSTS = 19 + N_EPH

MODEL_POINT_MASS = 0
MODEL_DEGREE2 = 1
MODEL_SH = 2
MODEL_POLYHEDRON = 3

STATUS_OK = 0
STATUS_MAX_STEPS = 1
STATUS_STEP_TOO_SMALL = 2
STATUS_NONFINITE = 3

# DOP853 tableau (Hairer, Norsett & Wanner; values as in scipy.integrate dop853_coefficients)
_C = np.array([0.                 , 0.05260015195876773, 0.0789002279381516 , 0.1183503419072274 ,
 0.2816496580927726 , 0.3333333333333333 , 0.25               , 0.3076923076923077 ,
 0.6512820512820513 , 0.6                , 0.8571428571428571 , 1.                 ,
 1.                 , 0.1                , 0.2                , 0.7777777777777778 ])
_A = np.array([[ 0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [ 5.2600151958767730e-02,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [ 1.9725056984537900e-02,  5.9175170953613701e-02,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [ 2.9587585476806851e-02,  0.0000000000000000e+00,  8.8762756430420545e-02,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [ 2.4136513415926669e-01,  0.0000000000000000e+00, -8.8454947932828609e-01,
   9.2483400326179199e-01,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [ 3.7037037037037035e-02,  0.0000000000000000e+00,  0.0000000000000000e+00,
   1.7082860872947386e-01,  1.2546768756682242e-01,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [ 3.7109375000000000e-02,  0.0000000000000000e+00,  0.0000000000000000e+00,
   1.7025221101954405e-01,  6.0216538980455959e-02, -1.7578125000000000e-02,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [ 3.7092000118504789e-02,  0.0000000000000000e+00,  0.0000000000000000e+00,
   1.7038392571223998e-01,  1.0726203044637328e-01, -1.5319437748624402e-02,
   8.2737891638140233e-03,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [ 6.2411095871607569e-01,  0.0000000000000000e+00,  0.0000000000000000e+00,
  -3.3608926294469414e+00, -8.6821934684172597e-01,  2.7592099699446710e+01,
   2.0154067550477894e+01, -4.3489884181069961e+01,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [ 4.7766253643826434e-01,  0.0000000000000000e+00,  0.0000000000000000e+00,
  -2.4881146199716677e+00, -5.9029082683684297e-01,  2.1230051448181193e+01,
   1.5279233632882423e+01, -3.3288210968984863e+01, -2.0331201708508627e-02,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [-9.3714243008598730e-01,  0.0000000000000000e+00,  0.0000000000000000e+00,
   5.1863724288440638e+00,  1.0914373489967295e+00, -8.1497870107469268e+00,
  -1.8520065659996959e+01,  2.2739487099350505e+01,  2.4936055526796523e+00,
  -3.0467644718982196e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [ 2.2733101475165380e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
  -1.0534495466737249e+01, -2.0008720582248625e+00, -1.7958931863118799e+01,
   2.7948884529419960e+01, -2.8589982771350235e+00, -8.8728569335306293e+00,
   1.2360567175794303e+01,  6.4339274601576357e-01,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [ 5.4293734116568765e-02,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  4.4503128927524092e+00,
   1.8915178993145003e+00, -5.8012039600105849e+00,  3.1116436695781990e-01,
  -1.5216094966251609e-01,  2.0136540080403034e-01,  4.4710615727772587e-02,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [ 5.6167502283047954e-02,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   2.5350021021662483e-01, -2.4623903747080250e-01, -1.2419142326381637e-01,
   1.5329179827876568e-01,  8.2010522956346907e-03,  7.5678976605456994e-03,
  -8.2979999999999998e-03,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [ 3.1834648163502142e-02,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  2.8300909672366776e-02,
   5.3541988307438566e-02, -5.4923748571390991e-02,  0.0000000000000000e+00,
   0.0000000000000000e+00, -1.0834732869724932e-04,  3.8257109083565839e-04,
  -3.4046500868740456e-04,  1.4131244367463250e-01,  0.0000000000000000e+00,
   0.0000000000000000e+00],
 [-4.2889630158379194e-01,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00, -4.6976214153611640e+00,
   7.6834211960625991e+00,  4.0689898183971103e+00,  3.5672718745528109e-01,
   0.0000000000000000e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
  -1.3990241651590145e-03,  2.9475147891527724e+00, -9.1509584721798696e+00,
   0.0000000000000000e+00]])
_B = np.array([ 0.054293734116568765,  0.                  ,  0.                  ,  0.                  ,
  0.                  ,  4.450312892752409   ,  1.8915178993145003  , -5.801203960010585   ,
  0.3111643669578199  , -0.1521609496625161  ,  0.20136540080403034 ,  0.04471061572777259 ])
_E3 = np.array([-0.18980075407240762,  0.                 ,  0.                 ,  0.                 ,
  0.                 ,  4.450312892752409  ,  1.8915178993145003 , -5.801203960010585  ,
 -0.4226823213237919 , -0.1521609496625161 ,  0.20136540080403034,  0.02265179219836082,
  0.                 ])
_E5 = np.array([ 0.01312004499419488 ,  0.                  ,  0.                  ,  0.                  ,
  0.                  , -1.2251564463762044  , -0.4957589496572502  ,  1.6643771824549864  ,
 -0.35032884874997366 ,  0.3341791187130175  ,  0.08192320648511571 , -0.022355307863886294,
  0.                  ])
_D = np.array([[-8.4289382761090135e+00,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  5.6671495351937773e-01,
  -3.0689499459498917e+00,  2.3846676565120699e+00,  2.1170345824450281e+00,
  -8.7139158377797299e-01,  2.2404374302607883e+00,  6.3157877876946877e-01,
  -8.8990336451333307e-02,  1.8148505520854727e+01, -9.1946323924783560e+00,
  -4.4360363875948936e+00],
 [ 1.0427508642579134e+01,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00,  2.4228349177525817e+02,
   1.6520045171727028e+02, -3.7454675472269020e+02, -2.2113666853125306e+01,
   7.7334326684722638e+00, -3.0674084731089398e+01, -9.3321305264302286e+00,
   1.5697238121770845e+01, -3.1139403219565178e+01, -9.3529243588444793e+00,
   3.5816841486394082e+01],
 [ 1.9985053242002433e+01,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00, -3.8703730874935178e+02,
  -1.8917813819516758e+02,  5.2780815920542364e+02, -1.1573902539959629e+01,
   6.8812326946963003e+00, -1.0006050966910838e+00,  7.7771377980534429e-01,
  -2.7782057523535082e+00, -6.0196695231264123e+01,  8.4320405506677162e+01,
   1.1992291136182789e+01],
 [-2.5693933462703750e+01,  0.0000000000000000e+00,  0.0000000000000000e+00,
   0.0000000000000000e+00,  0.0000000000000000e+00, -1.5418974869023643e+02,
  -2.3152937917604550e+02,  3.5763911791061412e+02,  9.3405324183624316e+01,
  -3.7458323136451632e+01,  1.0409964950896230e+02,  2.9840293426660502e+01,
  -4.3533456590011141e+01,  9.6324553959188279e+01, -3.9177261675615441e+01,
  -1.4972683625798564e+02]])

_SAFETY = 0.9
_MIN_FACTOR = 0.2
_MAX_FACTOR = 10.0
_ERR_EXP = -1.0 / 8.0
_N_STAGES = 12


@njit(cache=True)
def gravity_T(r_T, model, consts, sh_c, sh_s, pv, pf, pe, ped, pfd, acc, grad, a2, g2):
    """Gravity acceleration (m/s^2) and gradient (1/s^2) of the packed force model.

    Returns the potential (m^2/s^2). See the module docstring for ``model``
    and ``consts``; ``sh_c, sh_s`` are the tables of
    :func:`ideas_hpc.core.gravity.sh_derivative_tables`, ``pv, pf, pe, ped,
    pfd`` the polyhedron vertices, faces, edges, edge and face dyads (unused
    arrays may be empty); ``a2, g2`` are (3,), (3, 3) work arrays.
    """
    if model == MODEL_SH:
        kk = sh_c.shape[1]
        v = np.empty((kk, kk))
        w = np.empty((kk, kk))
        return sh_gravity(r_T, consts[K_SH_GM], consts[K_SH_RREF], sh_c, sh_s, acc, grad, v, w)
    if model == MODEL_POLYHEDRON:
        return polyhedron_gravity(r_T, consts[K_GRHO], pv, pf, pe, ped, pfd, acc, grad)
    u = point_mass(r_T, consts[K_MU], acc, grad)
    if model == MODEL_DEGREE2:
        u += degree2(r_T, consts[K_MU], consts[K_C20], consts[K_C22], a2, g2)
        for i in range(3):
            acc[i] += a2[i]
            for j in range(3):
                grad[i, j] += g2[i, j]
    return u


@njit(cache=True)
def srp_T(t, consts, out):
    """Cannonball SRP acceleration in T at time t (m/s^2), written to ``out``.

    ``consts`` must hold the ephemeris constants of
    :func:`ideas_hpc.core.ephemeris.ephemeris_precompute` at ``K_EPH``.
    """
    if consts[K_SRP] == 0.0:
        out[0] = 0.0
        out[1] = 0.0
        out[2] = 0.0
        return
    d = sun_T_fast(t, consts[K_EPH:K_EPH + N_EPH], out)
    f = -consts[K_SRP] / (d * d)
    out[0] *= f
    out[1] *= f
    out[2] *= f


@njit(cache=True)
def rhs(t, y, dy, model, consts, sh_c, sh_s, pv, pf, pe, ped, pfd):
    """Right-hand side for a 6-state (trajectory) or 42-state (with STM).

    Parameters
    ----------
    t : float
        s after t0 (the Sun ephemeris and the spin angle are referred to t0 = 0).
    y, dy : (6,) or (42,) float64
        State ``[r (m), v (m/s), Phi (row-major)]`` in T, and its derivative (output).
    model ... pfd
        Packed force model (module docstring).
    """
    _rhs_w(t, y, dy, model, consts, sh_c, sh_s, pv, pf, pe, ped, pfd,
           np.empty(3), np.empty((3, 3)), np.empty(3), np.empty((3, 3)), np.empty(3))


@njit(cache=True)
def _rhs_w(t, y, dy, model, consts, sh_c, sh_s, pv, pf, pe, ped, pfd, acc, grad, a2, g2, asrp):
    """:func:`rhs` with caller-owned work arrays (no allocation in the hot loop)."""
    w = consts[K_SPIN]
    gravity_T(y[:3], model, consts, sh_c, sh_s, pv, pf, pe, ped, pfd, acc, grad, a2, g2)
    srp_T(t, consts, asrp)
    x, yy = y[0], y[1]
    vx, vy, vz = y[3], y[4], y[5]
    dy[0] = vx
    dy[1] = vy
    dy[2] = vz
    # -2 w x v - w x (w x r), w = (0, 0, w)
    dy[3] = 2.0 * w * vy + w * w * x + acc[0] + asrp[0]
    dy[4] = -2.0 * w * vx + w * w * yy + acc[1] + asrp[1]
    dy[5] = acc[2] + asrp[2]
    if y.shape[0] == 42:
        # A21 = G - W W = G + diag(w^2, w^2, 0);  A22 = -2 W
        grad[0, 0] += w * w
        grad[1, 1] += w * w
        for j in range(6):
            p0 = y[6 + j]
            p1 = y[12 + j]
            p2 = y[18 + j]
            q0 = y[24 + j]
            q1 = y[30 + j]
            q2 = y[36 + j]
            dy[6 + j] = q0
            dy[12 + j] = q1
            dy[18 + j] = q2
            dy[24 + j] = grad[0, 0] * p0 + grad[0, 1] * p1 + grad[0, 2] * p2 + 2.0 * w * q1
            dy[30 + j] = grad[1, 0] * p0 + grad[1, 1] * p1 + grad[1, 2] * p2 - 2.0 * w * q0
            dy[36 + j] = grad[2, 0] * p0 + grad[2, 1] * p1 + grad[2, 2] * p2


@njit(cache=True)
def _rms(v, scale):
    s = 0.0
    for i in range(v.shape[0]):
        q = v[i] / scale[i]
        s += q * q
    return np.sqrt(s / v.shape[0])


@njit(cache=True)
def dop853(y0, t0, tf, rtol, atol, t_out, y_out, max_steps,
           model, consts, sh_c, sh_s, pv, pf, pe, ped, pfd):
    """Integrate ``y' = rhs(t, y)`` from t0 to tf with DOP853 and step control.

    Parameters
    ----------
    y0 : (n,) float64
        Initial state (n = 6 or 42), SI, frame T.
    t0, tf : float
        s, ``tf > t0``.
    rtol, atol : float
        Tolerances, as scipy's ``solve_ivp``.
    t_out : (T,) float64
        Sorted sample times in ``[t0, tf]`` (may be empty).
    y_out : (T, m) float64
        Output: the first ``m <= 6`` state components at ``t_out`` from the
        7th-order dense output (the extra stages use the 6-state only).
    max_steps : int
        Give up (status 1) after this many steps.
    model, consts, sh_c, sh_s, pv, pf, pe, ped, pfd
        Packed force model (module docstring).

    Returns
    -------
    y : (n,) float64
        State at tf.
    nfev : int
        Right-hand-side evaluations (the extra dense-output stages, which use
        the 6-state, are counted too).
    status : int
        0 success, 1 too many steps, 2 step too small, 3 non-finite state.
    """
    n = y0.shape[0]
    K = np.empty((16, n))
    wa = np.empty(3)
    wg = np.empty((3, 3))
    wa2 = np.empty(3)
    wg2 = np.empty((3, 3))
    ws = np.empty(3)
    y = y0.copy()
    ynew = np.empty(n)
    ytmp = np.empty(n)
    scale = np.empty(n)
    e3 = np.empty(n)
    e5 = np.empty(n)
    t = t0
    nfev = 0
    f = np.empty(n)
    _rhs_w(t, y, f,
               model, consts, sh_c, sh_s, pv, pf, pe, ped, pfd, wa, wg, wa2, wg2, ws)
    nfev += 1
    # initial step, Hairer et al. II.4 (as scipy select_initial_step)
    for i in range(n):
        scale[i] = atol + abs(y[i]) * rtol
    d0 = _rms(y, scale)
    d1 = _rms(f, scale)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    h0 = min(h0, tf - t0)
    for i in range(n):
        ytmp[i] = y[i] + h0 * f[i]
    _rhs_w(t0 + h0, ytmp, K[1],
               model, consts, sh_c, sh_s, pv, pf, pe, ped, pfd, wa, wg, wa2, wg2, ws)
    nfev += 1
    for i in range(n):
        e3[i] = K[1, i] - f[i]
    d2 = _rms(e3, scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    h_abs = min(100.0 * h0, h1)

    n_out = t_out.shape[0]
    m_out = y_out.shape[1] if n_out > 0 else 0
    k_out = 0
    while k_out < n_out and t_out[k_out] < t0:
        k_out += 1
    nsteps = 0
    status = STATUS_OK
    Kd = np.empty((16, 6))
    yd = np.empty(6)
    fd = np.empty(6)
    F = np.empty((7, 6))
    while t < tf:
        if nsteps >= max_steps:
            status = STATUS_MAX_STEPS
            break
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        if h_abs < min_step:
            h_abs = min_step
        rejected = False
        accepted = False
        while not accepted:
            if h_abs < min_step:
                status = STATUS_STEP_TOO_SMALL
                break
            t_new = t + h_abs
            if t_new > tf:
                t_new = tf
            h = t_new - t
            h_abs = abs(h)
            for i in range(n):
                K[0, i] = f[i]
            for s in range(1, _N_STAGES):
                for i in range(n):
                    acc = 0.0
                    for j in range(s):
                        acc += _A[s, j] * K[j, i]
                    ytmp[i] = y[i] + h * acc
                _rhs_w(t + _C[s] * h, ytmp, K[s],
               model, consts, sh_c, sh_s, pv, pf, pe, ped, pfd, wa, wg, wa2, wg2, ws)
            nfev += _N_STAGES - 1
            for i in range(n):
                acc = 0.0
                for j in range(_N_STAGES):
                    acc += _B[j] * K[j, i]
                ynew[i] = y[i] + h * acc
            _rhs_w(t_new, ynew, K[_N_STAGES],
               model, consts, sh_c, sh_s, pv, pf, pe, ped, pfd, wa, wg, wa2, wg2, ws)
            nfev += 1
            finite = True
            for i in range(n):
                scale[i] = atol + max(abs(y[i]), abs(ynew[i])) * rtol
                a3 = 0.0
                a5 = 0.0
                for j in range(_N_STAGES + 1):
                    a3 += _E3[j] * K[j, i]
                    a5 += _E5[j] * K[j, i]
                e3[i] = a3 / scale[i]
                e5[i] = a5 / scale[i]
                if not np.isfinite(ynew[i]):
                    finite = False
            if not finite:
                status = STATUS_NONFINITE
                break
            n5 = 0.0
            n3 = 0.0
            for i in range(n):
                n5 += e5[i] * e5[i]
                n3 += e3[i] * e3[i]
            if n5 == 0.0 and n3 == 0.0:
                err = 0.0
            else:
                err = h_abs * n5 / np.sqrt((n5 + 0.01 * n3) * n)
            if err < 1.0:
                if err == 0.0:
                    factor = _MAX_FACTOR
                else:
                    factor = min(_MAX_FACTOR, _SAFETY * err ** _ERR_EXP)
                if rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                accepted = True
            else:
                h_abs *= max(_MIN_FACTOR, _SAFETY * err ** _ERR_EXP)
                rejected = True
        if status != STATUS_OK:
            break
        # dense output on [t, t_new] for samples in the step (6-state only)
        if k_out < n_out and t_out[k_out] <= t_new:
            for s in range(_N_STAGES + 1):
                for i in range(6):
                    Kd[s, i] = K[s, i]
            for s in range(_N_STAGES + 1, 16):
                for i in range(6):
                    acc = 0.0
                    for j in range(s):
                        acc += _A[s, j] * Kd[j, i]
                    yd[i] = y[i] + h * acc
                _rhs_w(t + _C[s] * h, yd, fd,
               model, consts, sh_c, sh_s, pv, pf, pe, ped, pfd, wa, wg, wa2, wg2, ws)
                for i in range(6):
                    Kd[s, i] = fd[i]
            nfev += 3
            for i in range(6):
                dlt = ynew[i] - y[i]
                F[0, i] = dlt
                F[1, i] = h * Kd[0, i] - dlt
                F[2, i] = 2.0 * dlt - h * (Kd[_N_STAGES, i] + Kd[0, i])
                for q in range(4):
                    acc = 0.0
                    for j in range(16):
                        acc += _D[q, j] * Kd[j, i]
                    F[3 + q, i] = h * acc
            while k_out < n_out and t_out[k_out] <= t_new:
                x = (t_out[k_out] - t) / h
                x1 = 1.0 - x
                for i in range(m_out):
                    val = F[6, i] * x + F[5, i]
                    val = val * x1 + F[4, i]
                    val = val * x + F[3, i]
                    val = val * x1 + F[2, i]
                    val = val * x + F[1, i]
                    val = val * x1 + F[0, i]
                    y_out[k_out, i] = val * x + y[i]
                k_out += 1
        for i in range(n):
            y[i] = ynew[i]
            f[i] = K[_N_STAGES, i]
        t = t_new
        nsteps += 1
    return y, nfev, status


@njit(cache=True)
def propagate(r0, v0, t0, tf, with_stm, rtol, atol, t_out, y_out, max_steps,
              model, consts, sh_c, sh_s, pv, pf, pe, ped, pfd):
    """Propagate one spacecraft from ``(r0, v0)`` at t0 to tf (frame T, SI).

    ``with_stm`` adds ``Phi(t0) = I`` and returns the 42-state; samples of
    ``[r, v]`` at ``t_out`` go to ``y_out`` (``(T, 6)``). Returns
    ``(y_final, nfev, status)`` as :func:`dop853`.
    """
    n = 42 if with_stm else 6
    y0 = np.zeros(n)
    for i in range(3):
        y0[i] = r0[i]
        y0[3 + i] = v0[i]
    if with_stm:
        for i in range(6):
            y0[6 + 7 * i] = 1.0
    return dop853(y0, t0, tf, rtol, atol, t_out, y_out, max_steps,
                  model, consts, sh_c, sh_s, pv, pf, pe, ped, pfd)
