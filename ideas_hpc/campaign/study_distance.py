"""The closest-approach distance of ``ideas-hpc study`` (issue 42 deliverable 5: "offer
closest-approach distance from a short list: it trades GSD against line-of-sight rate and
navigation error"; :mod:`ideas_hpc.campaign.study`).

For each distance ``d`` of the list (the store's own, ``flyby.d_sep_km`` or the sizing's,
always a row) the store's campaign is validated again with ``flyby.d_sep_km = d`` and its
setup rebuilt (so the separation, grid-step and pointing checks of that distance apply),
a bank built from the same seed and scenario stream (common random numbers: the same
worlds, dispersions and navigation draws at every distance; only the ring's radius
differs), and the fewest N searched at the design's level, with the P of that fewest-N
swarm. No new physics; beside them, each distance's camera figures from the existing
closed forms (SPEC 7f; :mod:`ideas_hpc.flyby.pass_rates`, :mod:`ideas_hpc.flyby.sizing`)::

    GSD      = (d - R_av) IFOV                 ground sample at the sub-spacecraft point
                                               at closest approach (the sizing's h = d - R_av)
    omega_0  = v / d                           peak line-of-sight rate (at TCA)
    delta    = sigma_B / d                     pointing bias of the B-plane 1-sigma

with ``IFOV`` the instrument's (:func:`~ideas_hpc.flyby.usable.ifov_rad`), ``v`` the
encounter's speed (no LOS rate for the paper's slow pass: NaN) and ``sigma_B`` the
navigation's B-plane major 1-sigma (NaN without navigation). The best distance is the
one of fewest N, ties broken by the higher P of its fewest-N swarm.
"""

from __future__ import annotations

import copy
import dataclasses
import time

import numpy as np

from ideas_hpc.base import seeds
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.progress import log
from ideas_hpc.base.units import KM
from ideas_hpc.campaign.schema.design_table import check_distances as checked_distances

#: The option naming the list (InputError field).
OPTION = "--ca-distances-km"


def check_distances(distances_m) -> tuple:
    """The list as positive floats (m), else one :class:`InputError` naming the option
    (:func:`~ideas_hpc.campaign.schema.design_table.check_distances`, shared with the
    design's ``design.ca_distances_km``)."""
    return checked_distances(distances_m, OPTION)


def km_list(text: str, field: str) -> tuple:
    """``"100,30,10"`` (km) as positive lengths in m; one line naming ``field`` otherwise
    (the study's B-plane sigmas and closest-approach distances)."""
    try:
        vals = tuple(float(x) * KM for x in str(text).split(",") if x.strip())
    except ValueError:
        vals = ()
    if not vals or any(not v > 0 for v in vals):
        raise InputError(f"needs positive km separated by commas, got {text!r}", field=field)
    return vals


def parse_km(text: str) -> tuple:
    """``"100,157,300"`` (km) as distances in m (:func:`check_distances`)."""
    return check_distances(km_list(text, OPTION))


def distance_campaign(c, d_m: float):
    """The campaign ``c`` validated again with ``flyby.d_sep_km = d_m / 1 km``."""
    from ideas_hpc.campaign.schema.campaign_tables import validate_campaign

    data = copy.deepcopy(c.source.data)
    data.setdefault("flyby", {})["d_sep_km"] = float(d_m) / KM
    src = dataclasses.replace(c.source, data=data,
                              overrides=[*c.source.overrides, f"flyby.d_sep_km={d_m / KM:g}"])
    return validate_campaign(src)


def distance_setup(c, d_m: float):
    """The setup of ``c`` rebuilt at closest-approach distance ``d_m`` (m)."""
    from ideas_hpc.campaign.setup import setup_from_campaign

    return setup_from_campaign(distance_campaign(c, d_m))


def camera_ifov_rad(c, setup) -> float:
    """The instrument's IFOV (rad) at the setup's half-angle."""
    from ideas_hpc.flyby.usable import ifov_rad

    inst = c.config.instrument
    return ifov_rad(setup.eta_rad, pixels_across=inst.pixels_across,
                    pixel_pitch_m=inst.pixel_pitch_m, focal_length_m=inst.focal_length_m,
                    wavelength_m=inst.wavelength_m, aperture_m=inst.aperture_m)


def camera_figures(setup, d_m, ifov: float) -> dict:
    """GSD at closest approach (m), peak LOS rate (rad/s) and the B-plane 1-sigma's pointing
    bias (rad) at distances ``d_m`` (module docstring)."""
    from ideas_hpc.flyby.pass_rates import peak_los_rate_rad_s

    d = np.asarray(d_m, dtype=np.float64)
    enc, nav = setup.encounter, setup.navigation
    rate = np.full(d.shape, np.nan) if enc is None else np.array(
        [peak_los_rate_rad_s(enc.speed_m_s, x) for x in d.ravel()]).reshape(d.shape)
    sig = np.nan if nav is None or nav.error.sigma_major_m <= 0 else nav.error.sigma_major_m
    return {"gsd_m": (d - setup.sizing.r_av) * float(ifov), "los_rate_rad_s": rate,
            "pointing_bias_rad": sig / d}


def best_row(n, p) -> int:
    """Index of the fewest N (``n <= 0``: none reached), ties by the higher P; -1: none."""
    ok = [i for i in range(len(n)) if n[i] > 0]
    if not ok:
        return -1
    return min(ok, key=lambda i: (int(n[i]), -float(p[i]), i))


def distance_value(st, distances_m):
    """The distance answer (module docstring): ``xarray.Dataset`` over ``ca_distance``
    (ascending), the store's own distance included."""
    import xarray as xr

    from ideas_hpc.campaign.study_vars import answer_attrs, search_vars

    own = float(st.setup.d_sep_m)
    dist = sorted({float(d) for d in check_distances(distances_m)} | {own})
    rows = []
    for d in dist:
        setup, name = (st.setup, None) if d == own else (distance_setup(st.c, d),
                                                          f"ca-{d / KM:g}km")
        t0 = time.perf_counter()
        rows.append(st.fewest(setup, st.bank(setup, name),
                              recorded=st.design_search if name is None else None))
        log(f"closest approach {d / KM:g} km: bank and search in "
            f"{time.perf_counter() - t0:.1f} s")
    ifov = camera_ifov_rad(st.c, st.setup)
    cam = camera_figures(st.setup, dist, ifov)
    best = best_row([r["n"] for r in rows], [r["probability"] for r in rows])
    dim = "ca_distance"
    return xr.Dataset(
        {**search_vars(dim, rows),
         "gsd": (dim, cam["gsd_m"], {"units": "m", "long_name": "ground sample distance at "
                                     "closest approach, (d - R_av) IFOV"}),
         "los_rate": (dim, cam["los_rate_rad_s"], {"units": "rad/s", "long_name":
                                                   "peak line-of-sight rate v / d (at TCA)"}),
         "pointing_bias": (dim, cam["pointing_bias_rad"], {
             "units": "rad", "long_name": "B-plane 1-sigma over d (the pointing bias of "
                                          "tracking the predicted target at TCA)"})},
        coords={dim: (dim, np.array(dist), {"units": "m",
                                            "long_name": "closest-approach distance d_sep"})},
        attrs=answer_attrs(st, campaign_distance_m=own, ifov_rad=float(ifov), best=int(best),
                     best_distance_m=float(dist[best]) if best >= 0 else float("nan"),
                     best_rule="fewest N, ties by the higher P of the fewest-N swarm",
                     scenario_stream=seeds.SCENARIO_STREAM,
                     common_random_numbers="every bank: the same seed and scenario stream, "
                     "so the same worlds, dispersions and navigation draws; only the ring's "
                     "radius differs"))
