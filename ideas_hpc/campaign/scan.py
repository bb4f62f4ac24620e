"""Arrival-epoch scan: how mapping with lighting changes with the time of arrival (issue 14).

The swarm is targeted and its attitude computed once (the trajectory in the
body frame T does not depend on where the Sun is); the quality pass then runs
for each arrival epoch ``e`` with the Sun of the ephemeris at ``e + t``
(:meth:`ideas_hpc.flyby.flight.FlybySetup.sun_T`). Over one rotation period this
scans the body's rotation phase relative to the Sun, i.e. which side is lit
while the swarm passes.

    ideas-hpc scan-arrival campaigns/eros-flyby.toml --n 24 [--span-h 5.27] [--out scan.nc]
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import xarray as xr

from ideas_hpc.flyby.flight import fly
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.campaign.schema.kinds import KINDS
from ideas_hpc.campaign.schema.model_fields import flyby_errors
from ideas_hpc.mapping.coverage import compute_coverage

SCAN_ATTRS = {
    "coverage": {"units": "1", "long_name": "area fraction meeting the [coverage] requirement "
                 "(seen fraction when none is set)"},
    "coverage_seen": {"units": "1", "long_name": "area fraction observed"},
    "lit_fraction": {"units": "1", "long_name": "area fraction observed while lit"},
    "stereo_fraction": {"units": "1", "long_name": "area fraction with a stereo pair"},
    "sun_longitude": {"units": "rad", "long_name": "Sun longitude in frame T at flyby t0"},
    "sun_latitude": {"units": "rad", "long_name": "Sun latitude in frame T at flyby t0"},
}


def arrival_scan(setup, theta, periods=None, epochs=None) -> xr.Dataset:
    """Coverage with lighting versus arrival epoch.

    Parameters
    ----------
    setup : ideas_hpc.flyby.flight.FlybySetup
    theta : (N,) rad
        Swarm angles.
    periods : (N,) s, optional
        FoV sweep periods.
    epochs : (E,) s
        Arrival epochs after the body's element epoch.

    Returns
    -------
    xarray.Dataset
        Dim ``epoch`` (s): ``coverage``, ``coverage_seen``, ``lit_fraction``,
        ``stereo_fraction``, ``sun_longitude``, ``sun_latitude``.
    """
    ep = np.atleast_1d(np.asarray(epochs, dtype=np.float64))
    opts = setup.coverage if setup.coverage.wants_quality else replace(setup.coverage,
                                                                       quality=True)
    base = fly(setup.with_(coverage=replace(opts, quality=False, require_lit=False,
                                            max_resolution_m=None, max_emission_rad=None,
                                            max_incidence_rad=None, max_phase_rad=None,
                                            require_stereo=False, illumination=False)),
               theta, periods, counts=False)
    a = setup.body.shape.vertex_areas
    rows = {name: np.empty(ep.size) for name in SCAN_ATTRS}
    for m, e in enumerate(ep):
        sun = setup.sun_T(base.image_times, epoch=e)
        cov = compute_coverage(setup.body.shape, base.r_img_T, base.dcm_BT, base.image_times,
                               setup.eta_rad, setup.near_m, setup.far_m, options=opts, sun_T=sun,
                               counts=False)
        q = cov.quality
        rows["coverage"][m] = cov.coverage
        rows["coverage_seen"][m] = cov.coverage_seen
        rows["lit_fraction"][m] = float((a * q.lit).sum() / a.sum())
        rows["stereo_fraction"][m] = float((a * q.stereo).sum() / a.sum())
        rows["sun_longitude"][m] = math.atan2(sun[0, 1], sun[0, 0])
        rows["sun_latitude"][m] = math.asin(max(-1.0, min(1.0, sun[0, 2])))
    ds = xr.Dataset({name: (("epoch",), v) for name, v in rows.items()},
                    coords={"epoch": ("epoch", ep, {"units": "s",
                                                    "long_name": "arrival epoch after the "
                                                                 "element epoch"})})
    for name, attrs in SCAN_ATTRS.items():
        ds[name].attrs.update(attrs)
    return ds


@flyby_errors()   # flyby-layer errors under the file's keys
def scan_file(path, overrides=None, *, n: int = 24, span_h: float | None = None,
              out=None) -> xr.Dataset:
    """Scan ``n`` arrival epochs over ``span_h`` hours (default: one rotation period)
    from the campaign's ``flyby.epoch_s``; print a table, optionally write ``out``."""
    from ideas_hpc.base.errors import InputError
    from ideas_hpc.campaign.schema.campaign_tables import load

    c = load(path, overrides or [])
    if KINDS[c.kind].swarm != "file":
        able = " or ".join(k.name for k in KINDS.values() if k.swarm == "file")
        raise InputError(f"needs a {able} campaign, got {c.kind!r}", field="kind")
    if n < 1:
        raise InputError(f"must be >= 1, got {n}", field="--n")
    setup = setup_from_campaign(c)
    span = (2.0 * math.pi / setup.body.params.spin_rate if span_h is None
            else float(span_h) * 3600.0)
    if not span > 0.0:
        raise InputError(f"must be > 0, got {span_h}", field="--span-h")
    epochs = setup.epoch_s + span * np.arange(n) / n
    sw = c.config.swarm
    periods = setup.maneuver.swarm_periods(sw.sweep_periods_s)
    ds = arrival_scan(setup, sw.angles_rad, periods, epochs)
    print(f"{'epoch h':>8} {'sun lon deg':>11} {'coverage %':>10} {'seen %':>7} {'lit %':>6} "
          f"{'stereo %':>8}")
    for m in range(ds.sizes["epoch"]):
        print(f"{ds['epoch'].values[m] / 3600:8.3f} {math.degrees(ds['sun_longitude'][m]):11.1f}"
              f" {100 * float(ds['coverage'][m]):10.3f} {100 * float(ds['coverage_seen'][m]):7.2f}"
              f" {100 * float(ds['lit_fraction'][m]):6.2f} {100 * float(ds['stereo_fraction'][m]):8.2f}")
    best = int(np.argmax(ds["coverage"].values))
    cov = ds["coverage"].values
    if not (setup.coverage.require_lit or setup.coverage.illumination):
        # without a lighting requirement coverage ignores the Sun: every epoch maps the
        # same, and "the best epoch" would be the first of equals
        print("note: lighting is off (coverage counts what is seen, lit or not): set "
              "coverage.require_lit = true (--set coverage.require_lit=true) to rank "
              "arrival epochs by the sunlit area mapped; the lit % column is the Sun's "
              "share regardless")
    if np.ptp(cov) <= 1e-12:
        print(f"best arrival epoch: none, every epoch maps the same coverage "
              f"({100 * float(cov[best]):.3f} %)")
    else:
        print(f"best arrival epoch: {ds['epoch'].values[best]:.1f} s "
              f"(coverage {100 * float(ds['coverage'][best]):.3f} %)")
    if out is not None:
        ds.to_netcdf(out)
    return ds
