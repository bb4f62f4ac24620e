"""xarray datasets of campaign results; names, dims and units come from
:mod:`ideas_hpc.engine.variables` (SPEC section 9)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from ideas_hpc.mapping.coverage import quality_arrays
from ideas_hpc.engine.variables import with_attrs

AXES = ["x", "y", "z"]
WHEELS = ["1", "2", "3"]
N_SNAPSHOTS = 11

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
    """One flyby (:class:`~ideas_hpc.flyby.flight.FlybyOutcome`) as a dataset without ``sample``."""
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
        "half_angle_rad": float(setup.eta_rad), "near_m": float(setup.near_m),
        "far_m": float(setup.far_m), "d_sep_m": float(setup.d_sep_m),
        "altitude_m": float(s.altitude), "eta_nadir_rad": float(s.eta_nadir),
        "theta_max_rad": float(setup.theta_max_rad), "maneuver": setup.maneuver.campaign_name,
        "attitude_mode": setup.attitude_mode, "coverage_mode": setup.coverage.mode,
        "targeting_tolerance_m": float(setup.tol_m), "configuration": setup.configuration,
        **setup.geometry.attrs(setup),
    }


def base_attrs(c, setup) -> dict:
    """Global attrs of every campaign store besides the engine's provenance (resolved
    config and hash, code version, seed, creation time): kind, execution settings
    (not hashed), the campaign file, the setup's sizing and what its coverage is
    (``coverage_reference``, ``requirement_kind``, ``requirement``: issue 42)."""
    from ideas_hpc.engine.store_meta import config_json
    from ideas_hpc.campaign.schema.campaign_tables import EXECUTION_KNOBS
    from ideas_hpc.campaign.setup import requirement_attrs, requirement_from_campaign

    knobs = {k: getattr(getattr(c.config, k.split(".")[0]), k.split(".")[1])
             for k in EXECUTION_KNOBS}
    attrs = {"kind": c.kind, "execution": config_json(knobs),
             "campaign_file": str(c.source.path)}
    attrs.update(setup_attrs(setup))
    attrs.update(flown_body(c, setup))
    attrs.update(requirement_attrs(requirement_from_campaign(c)))
    return attrs


def flown_body(c, setup) -> dict:
    """What a store with a target prior flew (issue 42): a success-probability design
    flies one drawn world per scenario and validation sample, so its ``body`` is the
    prior (``"eros-class prior"``), not the nominal that defines the flight frame
    (``shape_model`` stays the nominal mesh's name); ``target_prior`` names the prior.
    Without a prior: nothing (``setup_attrs``' body stands)."""
    t = setup.target
    if t is None:
        return {}
    if getattr(c.config.design, "success_probability", None) is None:
        return {"target_prior": t.name}
    return {"body": f"{t.name} prior", "target_prior": t.name,
            "body_note": f"{t.name} prior: one drawn world per scenario and validation "
                         f"sample, around {setup.body.note}"}
