"""Encounter scan: coverage against approach declination and phase angle (issue 24).

For each ``(dec, phase)`` of a grid, the campaign's encounter (speed, window,
epoch, ``d_sep``, ``[coverage]`` requirement) is flown with that approach:
``v_inf`` at declination ``dec`` from the pole and right ascension set by the
phase angle (:func:`ideas_hpc.flyby.encounter.approach_angles`). Two numbers per
point: ``ring_coverage``, what the whole ring can map (the union of candidate
spacecraft every ``--step-deg`` of swarm angle: what any swarm on that ring
reaches at that grid step), and ``swarm_coverage``, what the campaign's own
``swarm.angles_rad`` map (when it has them). NaN where the Sun's direction makes
the phase angle unreachable at that declination.

    ideas-hpc scan-encounter campaigns/eros-fast-encounter.toml \
        [--dec-deg -60 -30 0 30 60 90] [--phase-deg 30 60 90 120] [--step-deg 10] [--out scan.nc] [--plot scan.png]
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from ideas_hpc.design.candidates import candidate_masks
from ideas_hpc.flyby.encounter import Encounter, approach_angles
from ideas_hpc.base.errors import InputError
from ideas_hpc.flyby.flight import fly
from ideas_hpc.campaign.setup import requirement_from_campaign, setup_from_campaign
from ideas_hpc.mapping.requirement import threshold_of
from ideas_hpc.campaign.schema.model_fields import flyby_errors
from ideas_hpc.base.units import DEG

SCAN_ATTRS = {
    "ring_coverage": {"units": "1", "long_name": "area fraction the ring's candidates map "
                      "together (every step_deg of swarm angle)"},
    "swarm_coverage": {"units": "1", "long_name": "area fraction the campaign's swarm maps"},
    "n_greedy": {"units": "1", "long_name": "spacecraft a greedy cover of the ring's candidates "
                 "needs to come within eps_tol of ring_coverage (an upper bound on the fewest)"},
    "approach_ra": {"units": "rad", "long_name": "right ascension of v_inf in T at closest "
                    "approach that gives the phase angle"},
}


def _greedy_n(rows, a, target) -> int:
    """Spacecraft a greedy cover needs to reach area ``target`` (rows (K, V) bool, areas a)."""
    covered = np.zeros(rows.shape[1], dtype=bool)
    for n in range(1, rows.shape[0] + 1):
        k = int(np.argmax((rows & ~covered) @ a))
        covered |= rows[k]
        if a @ covered >= target:
            return n
    return rows.shape[0]


def encounter_scan(setup, fb, decs_rad, phases_rad, *, step_rad: float = 10 * DEG,
                   theta=None, eps: float = 1e-3) -> xr.Dataset:
    """Coverage on a grid of approach declinations and phase angles (rad).

    ``setup`` is an encounter :class:`~ideas_hpc.flyby.flight.FlybySetup`, ``fb`` its
    validated ``[flyby]`` table (speed and window are kept).
    """
    if setup.encounter is None:
        raise InputError('needs flyby.geometry = "encounter"', field="flyby.geometry")
    decs = np.atleast_1d(np.asarray(decs_rad, dtype=np.float64))
    phases = np.atleast_1d(np.asarray(phases_rad, dtype=np.float64))
    keys = [(float(t), 0.0, 0) for t in np.arange(0.0, 2 * math.pi - 1e-9, step_rad)]
    a = setup.body.shape.vertex_areas
    t_ca = setup.encounter.t_ca_s
    sun = setup.sun_T([t_ca])[0]
    out = {name: np.full((decs.size, phases.size), np.nan) for name in SCAN_ATTRS}
    for i, dec in enumerate(decs):
        for j, ph in enumerate(phases):
            try:
                speed, ra, _ = approach_angles(speed_m_s=fb.speed_m_s, dec_rad=float(dec),
                                               phase_angle_rad=float(ph), sun_T_ca=sun)
            except InputError:
                continue
            s = setup.with_(encounter=Encounter(speed, ra, float(dec), t_ca))
            rows = candidate_masks(s, keys)
            ring = float(a @ rows.any(axis=0) / a.sum())
            out["ring_coverage"][i, j] = ring
            # within eps_tol of the ring's own reach (an upper bound on the fewest)
            out["n_greedy"][i, j] = _greedy_n(rows, a / a.sum(), threshold_of(ring, eps).need)
            out["approach_ra"][i, j] = ra
            if theta is not None:
                out["swarm_coverage"][i, j] = fly(s, theta, counts=False).coverage.coverage
    ds = xr.Dataset({k: (("dec", "phase"), v) for k, v in out.items()},
                    coords={"dec": ("dec", decs, {"units": "rad", "long_name": "approach "
                                                  "declination from the equator"}),
                            "phase": ("phase", phases, {"units": "rad",
                                                        "long_name": "phase angle"})},
                    attrs={"step_rad": float(step_rad), "speed_m_s": setup.encounter.speed_m_s,
                           "d_sep_m": float(setup.d_sep_m),
                           "shape_model": setup.body.shape.name})
    for name, attrs in SCAN_ATTRS.items():
        ds[name].attrs.update(attrs)
    return ds


@flyby_errors()   # flyby-layer errors under the file's keys
def scan_encounter_file(path, overrides=None, *, decs_deg=None, phases_deg=None,
                        step_deg: float = 10.0, out=None, plot=None) -> xr.Dataset:
    """Scan a campaign's encounter over ``decs_deg`` x ``phases_deg``; print a table."""
    from ideas_hpc.campaign.schema.campaign_tables import load

    c = load(path, overrides or [])
    setup = setup_from_campaign(c)
    if not step_deg > 0:
        raise InputError(f"must be > 0, got {step_deg}", field="--step-deg")
    decs = [-60.0, -30.0, 0.0, 30.0, 60.0, 90.0] if decs_deg is None else decs_deg
    phases = [30.0, 60.0, 90.0, 120.0] if phases_deg is None else phases_deg
    theta = c.config.swarm.angles_rad
    ds = encounter_scan(setup, c.config.flyby, np.radians(decs), np.radians(phases),
                        step_rad=math.radians(step_deg), theta=theta,
                        eps=requirement_from_campaign(c).eps_tol)
    what = "ring coverage % [greedy N]" + (" (swarm %)" if theta else "")
    print(f"{what} by approach declination (rows, deg) and phase angle (columns, deg), "
          f"{setup.encounter.speed_m_s / 1e3:g} km/s, d_sep {setup.d_sep_m / 1e3:.4g} km")
    print(f"{'dec':>6} " + " ".join(f"{p:>18g}" for p in phases))
    for i, d in enumerate(decs):
        cells = []
        for j in range(len(phases)):
            r = ds["ring_coverage"].values[i, j]
            sw = ds["swarm_coverage"].values[i, j]
            n = ds["n_greedy"].values[i, j]
            cells.append(f"{'-':>18}" if np.isnan(r) else
                         f"{100 * r:7.2f} [{n:2.0f}]" + (f" ({100 * sw:5.1f})" if theta else ""))
        print(f"{d:6g} " + " ".join(f"{x:>18}" for x in cells))
    if out is not None:
        ds.to_netcdf(out)
    if plot is not None:
        from ideas_hpc.plots.encounter import scan_map

        print(f"figure: {scan_map(ds, plot)}")
    return ds
