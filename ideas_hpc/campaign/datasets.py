"""xarray datasets of campaign results, with the SPEC section 9 names and units.

Dims: ``sample``, ``spacecraft``, ``time``, ``iteration``, ``vertex``,
``axis`` (x, y, z), ``wheel``, ``generation``, ``individual``, ``gene``, plus
``face``/``corner`` for the stored mesh and ``snapshot``/``row``/``col`` for
camera DCMs at a few instants (FoV pyramid figures).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..mapping import QUALITY_VARS, quality_arrays  # noqa: F401  (store layout)

AXES = ["x", "y", "z"]
WHEELS = ["1", "2", "3"]
N_SNAPSHOTS = 11

VAR_ATTRS = {
    "swarm_angle": {"units": "rad", "long_name": "swarm angle theta_i"},
    "sweep_period": {"units": "s", "long_name": "FoV sweep period P_i"},
    "position": {"units": "m", "long_name": "spacecraft position, frame T"},
    "velocity": {"units": "m/s", "long_name": "spacecraft velocity, frame T"},
    "targeting_miss": {"units": "m", "long_name": "|dr_k| per Newton iteration (NaN: not run)"},
    "targeting_v0": {"units": "m/s", "long_name": "targeted initial velocity, frame T"},
    "sigma_error": {"units": "1", "long_name": "MRP attitude error sigma_B/R"},
    "omega_error": {"units": "rad/s", "long_name": "rate error omega_B/R, frame B"},
    "wheel_speed": {"units": "rad/s", "long_name": "reaction wheel speed Omega"},
    "wheel_torque": {"units": "N m", "long_name": "reaction wheel torque u_s"},
    "camera_dcm_BT": {"units": "1", "long_name": "camera DCM [BT] (B <- T) at snapshots"},
    "observed": {"units": "1", "long_name": "vertex observed (paper eq. 26)"},
    "first_seen": {"units": "s", "long_name": "first time the vertex was imaged (NaN: never)"},
    "times_seen": {"units": "1", "long_name": "number of images that saw the vertex"},
    "coverage": {"units": "1", "long_name": "area-weighted fraction observed (mapped when "
                 "a [coverage] requirement is set)"},
    "coverage_seen": {"units": "1", "long_name": "area-weighted fraction observed"},
    "lit": {"units": "1", "long_name": "sunlit and unshadowed at some observation"},
    "best_resolution": {"units": "m", "long_name": "best effective ground sample "
                        "rho*range/cos(emission) (NaN: never observed)"},
    "emission_at_best": {"units": "rad", "long_name": "emission angle at the best-resolution "
                         "observation"},
    "incidence_at_best": {"units": "rad", "long_name": "incidence angle at the best-resolution "
                          "observation"},
    "phase_at_best": {"units": "rad", "long_name": "phase angle at the best-resolution "
                      "observation"},
    "n_spacecraft_seen": {"units": "1", "long_name": "spacecraft that observed the vertex"},
    "stereo": {"units": "1", "long_name": "two usable observations with a convergence angle "
               "in [stereo_min, stereo_max]"},
    "mapped": {"units": "1", "long_name": "vertex meets the [coverage] requirement"},
    "coverage_count": {"units": "1", "long_name": "vertex-count fraction observed"},
    "vertex_position": {"units": "m", "long_name": "shape model vertex, frame T"},
    "vertex_area": {"units": "m^2", "long_name": "vertex area (1/3 of adjacent faces)"},
    "face_vertices": {"units": "1", "long_name": "vertex indices of each face"},
    "best_fitness": {"units": "1", "long_name": "best fitness"},
    "mean_fitness": {"units": "1", "long_name": "population mean fitness"},
    "population": {"units": "1", "long_name": "final population genomes"},
    "fitness": {"units": "1", "long_name": "fitness of the final population"},
    "population_coverage": {"units": "1", "long_name": "area coverage of the final population"},
    "best_genome": {"units": "1", "long_name": "best genome"},
}


def with_attrs(ds: xr.Dataset) -> xr.Dataset:
    for name, attrs in VAR_ATTRS.items():
        if name in ds:
            ds[name].attrs.update(attrs)
    return ds


def mesh_vars(shape) -> dict:
    """The shape model, so reports draw the body without the data path."""
    return {
        "vertex_position": (("vertex", "axis"), shape.vertices_T),
        "vertex_area": (("vertex",), shape.vertex_areas),
        "face_vertices": (("face", "corner"), shape.faces.astype(np.int32)),
    }


def snapshot_indices(n_images: int, n: int = N_SNAPSHOTS) -> np.ndarray:
    return np.unique(np.linspace(0, n_images - 1, n).round().astype(int))


def flyby_dataset(setup, out) -> xr.Dataset:
    """One flyby (:class:`~ideas_hpc.flyby.FlybyOutcome`) as a dataset without ``sample``."""
    dec = setup.decimate
    tg = out.targeting
    pos = tg.position_T[:, ::dec]
    vel = tg.velocity_T[:, ::dec]
    times = tg.times[::dec]
    snaps = snapshot_indices(out.image_times.size)
    data = {
        "swarm_angle": (("spacecraft",), out.theta),
        "position": (("spacecraft", "time", "axis"), pos),
        "velocity": (("spacecraft", "time", "axis"), vel),
        "targeting_miss": (("spacecraft", "iteration"), tg.miss),
        "targeting_v0": (("spacecraft", "axis"), tg.v0_T),
        "camera_dcm_BT": (("spacecraft", "snapshot", "row", "col"), out.dcm_BT[:, snaps]),
        "snapshot_time": (("snapshot",), out.image_times[snaps]),
        "observed": (("vertex",), out.coverage.observed),
        "first_seen": (("vertex",), out.coverage.first_seen),
        "times_seen": (("vertex",), out.coverage.times_seen.astype(np.int32)),
        "coverage": ((), out.coverage.coverage),
        "coverage_count": ((), out.coverage.coverage_count),
        "coverage_seen": ((), out.coverage.coverage_seen),
        **{name: (("vertex",), a) for name, a in quality_arrays(out.coverage).items()},
        **mesh_vars(setup.body.shape),
    }
    if out.periods is not None:
        data["sweep_period"] = (("spacecraft",), out.periods)
    att = out.attitude
    if att is not None:
        n_t = min(att.times.size, times.size)
        for name in ("sigma_error", "omega_error"):
            data[name] = (("spacecraft", "time", "axis"), getattr(att, name)[0][:, :n_t])
        for name in ("wheel_speed", "wheel_torque"):
            data[name] = (("spacecraft", "time", "wheel"), getattr(att, name)[0][:, :n_t])
        data["max_wheel_torque"] = (("spacecraft",), att.max_torque[0])
        data["max_wheel_momentum"] = (("spacecraft",), att.max_momentum[0])
    coords = {"spacecraft": np.arange(out.theta.size), "time": times,
              "iteration": np.arange(tg.miss.shape[1]), "axis": AXES, "wheel": WHEELS,
              "vertex": np.arange(setup.body.shape.n_vertices)}
    ds = xr.Dataset(data, coords=coords)
    ds["time"].attrs["units"] = "s"
    return with_attrs(ds)


def setup_attrs(setup) -> dict:
    """Scalars every report needs (SI), as global attrs."""
    s = setup.sizing
    return {
        "body": setup.body.name, "body_note": setup.body.note,
        "shape_model": setup.body.shape.name,
        "half_angle_rad": float(setup.eta), "near_m": float(setup.near),
        "far_m": float(setup.far), "d_sep_m": float(setup.d_sep),
        "altitude_m": float(s.altitude), "eta_nadir_rad": float(s.eta_nadir),
        "theta_max_rad": float(setup.theta_max), "maneuver": setup.maneuver,
        "attitude_mode": setup.attitude_mode, "coverage_mode": setup.coverage.mode,
        "targeting_tolerance_m": float(setup.tol), "configuration": setup.configuration,
    }


def base_attrs(c, setup) -> dict:
    """Global attrs of every campaign store: kind, resolved config and its hash, code
    version, seed, execution settings (not hashed) and the setup's sizing."""
    import time

    from .._version import code_version
    from ..engine.store import config_hash, config_json
    from .schema import EXECUTION_KNOBS, resolved_config

    cfg = resolved_config(c)
    knobs = {k: getattr(getattr(c.config, k.split(".")[0]), k.split(".")[1])
             for k in EXECUTION_KNOBS}
    attrs = {"kind": c.kind, "config": config_json(cfg), "config_hash": config_hash(cfg),
             "execution": config_json(knobs), "code_version": code_version(),
             "campaign_seed": int(c.config.seed), "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
             "campaign_file": str(c.source.path)}
    attrs.update(setup_attrs(setup))
    return attrs
