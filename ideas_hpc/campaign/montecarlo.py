"""Monte Carlo campaigns over initial attitudes and perturbations (SPEC section 8).

The swarm's trajectories are designed once on the nominal model (targeted
``v0``). Each sample then flies that design open loop through its own world:

* initial attitude, body rates and wheel speeds (SPEC section 5);
* C20, C22 and GM scaled by ``1 + sigma * N(0, 1)``;
* SRP reflectivity uniform in ``[reflectivity_min, reflectivity_max]``;
* initial position and velocity errors, ``N(0, sigma)`` per axis;
* spacecraft failures: exactly ``failures_k`` of N lost, and/or each lost with
  ``failure_probability``;
* camera misalignment: a fixed rotation about a random axis by ``N(0, sigma)``.

Seeds (:mod:`ideas_hpc.seeds`): sample ``k`` of campaign seed ``s`` owns
``SeedSequence(s, spawn_key=(k,))``.
Its attitude initial conditions come from that sequence itself (so they equal
:func:`ideas_hpc.attitude.initial_conditions` ``(s, k, N)``), every other
dispersion from its child ``SeedSequence(s, spawn_key=(k, 1))``, drawn in a
fixed order whether or not a dispersion is switched on (so switching one on
does not shift the others). Every draw is stored, so a sample re-runs alone:
``ideas_hpc.campaign.montecarlo.run_sample(campaign, k)``.

Work is split into chunks of samples (``run.chunk_size``); each chunk is one
dask task that flies its samples and writes its region of the store
(:mod:`ideas_hpc.engine`).
"""

from __future__ import annotations

import functools
import sys
from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..attitude import initial_conditions
from ..core.frames import dcm_RT
from ..core.mrp import mrp_from_dcm
from ..engine.runner import run_campaign
from ..flyby import FlybySetup, camera_dcms, endpoints, misalignment_dcms, setup_from_campaign
from ..mapping import compute_coverage
from ..seeds import sample_rng
from ..trajectory import propagate_swarm, target_swarm
from . import datasets
from .schema import Campaign

DISPERSION_CHILD = 1


@dataclass
class Draws:
    """Every random quantity of one sample (SI)."""

    sigma0: np.ndarray          # (N, 3)
    omega0: np.ndarray          # (N, 3) rad/s
    wheel0: np.ndarray          # (N, 3) rad/s
    c20_factor: float
    c22_factor: float
    gm_factor: float
    reflectivity: float
    position_error: np.ndarray  # (N, 3) m
    velocity_error: np.ndarray  # (N, 3) m/s
    active: np.ndarray          # (N,) bool
    misalignment_prv: np.ndarray  # (N, 3) rad


def draw_sample(mc: dict, seed: int, k: int, theta: np.ndarray, setup: FlybySetup) -> Draws:
    """The dispersions of sample ``k`` (see the module docstring for the streams)."""
    n = theta.size
    if mc["attitude_dispersion"]:
        s0, w0, W0 = initial_conditions(seed, k, n)
    else:
        s0, w0, W0 = reference_start(setup, theta)
    rng = sample_rng(seed, k, DISPERSION_CHILD)
    z = rng.standard_normal(3)
    refl = rng.uniform(0.0, 1.0)
    dr = rng.standard_normal((n, 3))
    dv = rng.standard_normal((n, 3))
    perm = rng.permutation(n)
    bern = rng.uniform(0.0, 1.0, n)
    axes = rng.standard_normal((n, 3))
    angles = rng.standard_normal(n)
    active = np.ones(n, dtype=bool)
    if mc["failures_k"]:
        active[perm[:mc["failures_k"]]] = False
    active &= bern >= mc["failure_probability"]
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    return Draws(
        sigma0=s0, omega0=w0, wheel0=W0,
        c20_factor=1.0 + mc["sigma_c20_pct"] / 100.0 * z[0],
        c22_factor=1.0 + mc["sigma_c22_pct"] / 100.0 * z[1],
        gm_factor=1.0 + mc["sigma_gm_pct"] / 100.0 * z[2],
        reflectivity=mc["reflectivity_min"] + (mc["reflectivity_max"] - mc["reflectivity_min"])
        * refl,
        position_error=mc["sigma_position_m"] * dr,
        velocity_error=mc["sigma_velocity_mm_s"] * dv,
        active=active,
        misalignment_prv=axes * (mc["sigma_misalignment_deg"] * angles)[:, None])


def reference_start(setup: FlybySetup, theta: np.ndarray):
    """Initial state on the reference (no attitude dispersion): ``B = R_i`` at t0
    (``[TN](t0) = I``), turning with the body at its spin rate; wheels at rest."""
    ws = setup.body.params.spin_rate
    n = theta.size
    s0 = np.empty((n, 3))
    w0 = np.empty((n, 3))
    eye = np.eye(3)
    for i in range(n):
        c = dcm_RT(float(theta[i]), eye)
        s0[i] = mrp_from_dcm(c)
        w0[i] = c @ np.array([0.0, 0.0, ws])
    return s0, w0, np.zeros((n, 3))


@dataclass(frozen=True)
class Nominal:
    """The designed swarm: angles, periods and the nominal targeted trajectory."""

    theta: np.ndarray
    periods: np.ndarray | None
    r0_T: np.ndarray
    v0_T: np.ndarray
    times: np.ndarray
    position_T: np.ndarray
    velocity_T: np.ndarray
    miss: np.ndarray

    def for_tasks(self) -> "Nominal":
        """What a chunk task needs (start states and arrival points): the sampled
        trajectory stays on the client instead of being shipped with every task."""
        return Nominal(self.theta, self.periods, self.r0_T, self.v0_T, self.times[-1:],
                       np.ascontiguousarray(self.position_T[:, -1:]),
                       np.ascontiguousarray(self.velocity_T[:, -1:]), self.miss)


def design_nominal(setup: FlybySetup, theta, periods) -> Nominal:
    th = np.asarray(theta, dtype=float)
    r0, rt = endpoints(setup, th)
    tg = target_swarm(setup.body, r0, rt, setup.t0, setup.tf, force_model=setup.force_model,
                      dt_sample=setup.dt, tol=setup.tol, max_iter=setup.max_iter)
    return Nominal(th, None if periods is None else np.asarray(periods, float), r0, tg.v0_T,
                   tg.times, tg.position_T, tg.velocity_T, tg.miss)


def fly_sample(setup: FlybySetup, nom: Nominal, d: Draws):
    """One Monte Carlo sample: open-loop flight, attitude, coverage. Returns a dict."""
    p = setup.body.params
    override = {"mu": p.mu * d.gm_factor, "c20": p.c20 * d.c20_factor,
                "c22": p.c22 * d.c22_factor, "reflectivity": d.reflectivity}
    _, pos, _ = propagate_swarm(setup.body, nom.r0_T + d.position_error, nom.v0_T
                                + d.velocity_error, setup.t0, setup.tf,
                                force_model=setup.force_model, dt_sample=setup.dt,
                                params_override=override)
    r_img = np.ascontiguousarray(pos[:, ::setup.image_every])
    dcm, att = camera_dcms(setup, nom.theta, nom.periods, sigma0=d.sigma0, omega0=d.omega0,
                           wheel0=d.wheel0)
    mis = misalignment_dcms(d.misalignment_prv)
    dcm = np.ascontiguousarray(np.matmul(mis[:, None], dcm))  # [CB][BT] per image
    sun = setup.sun_T() if setup.coverage.needs_sun else None
    cov = compute_coverage(setup.body.shape, r_img, dcm, setup.image_times, setup.eta,
                           setup.near, setup.far, options=setup.coverage, sun_T=sun,
                           active=d.active)
    out = {"coverage": cov.coverage, "coverage_count": cov.coverage_count,
           "coverage_seen": cov.coverage_seen, **datasets.quality_arrays(cov),
           "observed": cov.observed, "first_seen": cov.first_seen,
           "times_seen": cov.times_seen, "arrival_error": np.linalg.norm(
               pos[:, -1] - nom.position_T[:, -1], axis=1)}
    if att is not None:
        for name in ("sigma_error", "omega_error", "wheel_speed", "wheel_torque"):
            out[name] = getattr(att, name)[0]
    return out


SAMPLE_DRAW_VARS = ("sigma0", "omega0", "wheel0", "position_error", "velocity_error",
                    "misalignment_prv")


def mc_chunk(chunk_id: int, start: int, stop: int, *, setup: FlybySetup, nominal: Nominal,
             mc: dict, seed: int) -> dict:
    """Chunk task: fly samples ``start..stop-1`` and return their arrays (sample first)."""
    rows = []
    for k in range(start, stop):
        d = draw_sample(mc, seed, k, nominal.theta, setup)
        r = fly_sample(setup, nominal, d)
        r.update({name: getattr(d, name) for name in SAMPLE_DRAW_VARS})
        r.update({"c20": setup.body.params.c20 * d.c20_factor,
                  "c22": setup.body.params.c22 * d.c22_factor,
                  "mu": setup.body.params.mu * d.gm_factor, "reflectivity": d.reflectivity,
                  "active": d.active, "n_failed": int((~d.active).sum())})
        rows.append(r)
    return {name: np.stack([np.asarray(r[name]) for r in rows]) for name in rows[0]}


def _lazy(shape, dtype):
    import dask.array as da

    return da.zeros(shape, dtype=dtype, chunks=shape)


def mc_template(setup: FlybySetup, nom: Nominal, n_samples: int) -> xr.Dataset:
    """Store layout: per-sample variables (declared) and the nominal design (written)."""
    ns, n = int(n_samples), nom.theta.size
    nv = setup.body.shape.n_vertices
    dec = setup.decimate
    times = nom.times[::dec]
    nt = times.size
    simulated = setup.attitude_mode == "simulated"
    s = ("sample",)
    v = {
        "coverage": (s, _lazy((ns,), np.float64)),
        "coverage_count": (s, _lazy((ns,), np.float64)),
        "coverage_seen": (s, _lazy((ns,), np.float64)),
        "observed": (s + ("vertex",), _lazy((ns, nv), bool)),
        "first_seen": (s + ("vertex",), _lazy((ns, nv), np.float64)),
        "times_seen": (s + ("vertex",), _lazy((ns, nv), np.int32)),
        "arrival_error": (s + ("spacecraft",), _lazy((ns, n), np.float64),
                          {"units": "m", "long_name": "final position minus nominal"}),
        "c20": (s, _lazy((ns,), np.float64), {"units": "m^2", "long_name": "C20 (dispersed)"}),
        "c22": (s, _lazy((ns,), np.float64), {"units": "m^2", "long_name": "C22 (dispersed)"}),
        "mu": (s, _lazy((ns,), np.float64), {"units": "m^3/s^2", "long_name": "GM (dispersed)"}),
        "reflectivity": (s, _lazy((ns,), np.float64), {"units": "1"}),
        "active": (s + ("spacecraft",), _lazy((ns, n), bool),
                   {"long_name": "spacecraft working (False: failed)"}),
        "n_failed": (s, _lazy((ns,), np.int32), {"long_name": "failed spacecraft"}),
        "sigma0": (s + ("spacecraft", "axis"), _lazy((ns, n, 3), np.float64),
                   {"units": "1", "long_name": "initial sigma_BN"}),
        "omega0": (s + ("spacecraft", "axis"), _lazy((ns, n, 3), np.float64),
                   {"units": "rad/s", "long_name": "initial omega_BN_B"}),
        "wheel0": (s + ("spacecraft", "wheel"), _lazy((ns, n, 3), np.float64),
                   {"units": "rad/s", "long_name": "initial wheel speeds"}),
        "position_error": (s + ("spacecraft", "axis"), _lazy((ns, n, 3), np.float64),
                           {"units": "m", "long_name": "initial position error, frame T"}),
        "velocity_error": (s + ("spacecraft", "axis"), _lazy((ns, n, 3), np.float64),
                           {"units": "m/s", "long_name": "initial velocity error, frame T"}),
        "misalignment_prv": (s + ("spacecraft", "axis"), _lazy((ns, n, 3), np.float64),
                             {"units": "rad", "long_name": "camera misalignment (PRV)"}),
        "swarm_angle": (("spacecraft",), nom.theta),
        "position": (("spacecraft", "time", "axis"), nom.position_T[:, ::dec]),
        "velocity": (("spacecraft", "time", "axis"), nom.velocity_T[:, ::dec]),
        "targeting_miss": (("spacecraft", "iteration"), nom.miss),
        **datasets.mesh_vars(setup.body.shape),
    }
    if setup.coverage.wants_quality:
        for name, dt in datasets.QUALITY_VARS.items():
            v[name] = (s + ("vertex",), _lazy((ns, nv), dt))
    if nom.periods is not None:
        v["sweep_period"] = (("spacecraft",), nom.periods)
    if simulated:
        for name, last in (("sigma_error", "axis"), ("omega_error", "axis"),
                           ("wheel_speed", "wheel"), ("wheel_torque", "wheel")):
            v[name] = (s + ("spacecraft", "time", last), _lazy((ns, n, nt, 3), np.float64))
    ds = xr.Dataset(v, coords={"sample": np.arange(ns), "spacecraft": np.arange(n),
                               "time": ("time", times, {"units": "s"}),
                               "iteration": np.arange(nom.miss.shape[1]),
                               "axis": datasets.AXES, "wheel": datasets.WHEELS,
                               "vertex": np.arange(nv)})
    return datasets.with_attrs(ds)


def _prepare(c: Campaign):
    setup = setup_from_campaign(c)
    sw = c.cfg["swarm"]
    periods = np.asarray(sw["sweep_periods_min"]) if setup.maneuver == "fov" else None
    nom = design_nominal(setup, sw["angles_rad"], periods)
    return setup, nom


def run_sample(c: Campaign, k: int) -> dict:
    """Re-run sample ``k`` of a campaign alone (same numbers as in the store)."""
    setup, nom = _prepare(c)
    return mc_chunk(k, k, k + 1, setup=setup, nominal=nom, mc=c.cfg["monte_carlo"],
                    seed=c.cfg["seed"])


def run_monte_carlo(c: Campaign, out, *, workers=None, scheduler=None, resume=False,
                    cluster="local", slurm_config=None, progress=True):
    """Kind ``monte-carlo``: chunked, resumable, on dask (SPEC section 8)."""
    from .run import _base_attrs, resolved

    setup, nom = _prepare(c)
    print(f"body: {setup.body.note}", file=sys.stderr, flush=True)
    mc = c.cfg["monte_carlo"]
    n = mc["samples"]
    template = mc_template(setup, nom, n)
    fn = functools.partial(mc_chunk, setup=setup, nominal=nom.for_tasks(), mc=mc,
                           seed=c.cfg["seed"])
    attrs = _base_attrs(c, setup)
    for key in ("config", "config_hash"):
        attrs.pop(key)
    summary = run_campaign(out, template, fn, config=resolved(c), campaign_seed=c.cfg["seed"],
                           chunk_size=c.cfg["run"]["chunk_size"], attrs=attrs, resume=resume,
                           workers=workers, scheduler=scheduler, cluster=cluster,
                           slurm_config=slurm_config, progress=progress)
    print(str(summary), file=sys.stderr, flush=True)
    return summary
