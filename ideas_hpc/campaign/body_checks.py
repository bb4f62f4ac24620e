"""Checks of a campaign against its body, once the body and the flyby are known (issue 32).

A custom body used to run on whatever it was given: a mesh in metres read as km
(a 500 km body of density 2e-6 kg/m^3), a mesh whose origin lies outside the body,
a candidate grid of 360,000 angles, dispersions larger than the field of view.
These checks refuse (an :class:`~ideas_hpc.base.errors.InputError` naming the key, exit 2)
what cannot be meant, and warn (one line on stderr naming the key) about what is
legal but will not map the body:

* refused: implied density outside :data:`~ideas_hpc.body.mass_properties.DENSITY_RANGE_KG_M3`
  (``body.length_unit``, or ``body.params`` for a built-in shape);
* refused: constant-density centre of mass farther than 5 % of the mean radius from the
  mesh origin (``body.name``);
* refused: a design grid with more than :data:`GRID_PER_SEPARATION` candidate angles
  inside the minimum separation angle ``2 asin(s / 2 d_sep)`` (the design's key for its
  step): no two of them can fly together, and the bank's cost grows with each;
* warned: a 3-sigma pointing dispersion (``monte_carlo.sigma_misalignment_deg``, or
  ``monte_carlo.sigma_position_m`` over the altitude) beyond the camera's half angle.
"""

from __future__ import annotations

import math
import sys

from ideas_hpc.body.bodies import BUILTIN
from ideas_hpc.body.mass_properties import (com_problem, density_problem, implied_density,
                                            mean_radius)
from ideas_hpc.campaign.schema.design_checks import step_key
from ideas_hpc.campaign.schema.kinds import KINDS
from ideas_hpc.base.errors import InputError
from ideas_hpc.flyby.swarm_geometry import min_separation_angle
from ideas_hpc.base.units import DEG

#: Most candidate angles allowed within one minimum-separation angle.
GRID_PER_SEPARATION = 10
#: Sigmas of a dispersion compared with the field of view (99.7 % of normal draws).
N_SIGMA = 3.0


def warn_field(field: str, message: str) -> None:
    """One warning line on stderr that names the key (``ideas-hpc: warning: key: ...``)."""
    print(f"ideas-hpc: warning: {field}: {message}", file=sys.stderr)


def check_body(c, body) -> None:
    """Refuse an implausible density or a mesh origin away from the centre of mass."""
    shape = body.shape
    props = shape.mass_properties
    problem = density_problem(implied_density(body.params.mu, props.volume_m3))
    if problem:
        b = c.config.body
        from_file = b.shape is not None or str(b.name).lower() not in BUILTIN
        key = "body.length_unit" if from_file else "body.params"
        raise c.error(f"{problem} (body.length_unit = {c.config.body.length_unit!r})", key)
    problem = com_problem(props, mean_radius(props.volume_m3))
    if problem:
        raise c.error(problem, "body.name")


def check_grid_step(c, d_sep_m: float) -> None:
    """Refuse a design grid far finer than the minimum separation can use."""
    cfg = c.config
    kind = KINDS[cfg.kind]
    if not kind.designs:
        return
    d = cfg.design
    ga = d.method in kind.continuous_methods
    step = d.angle_step_rad if ga else d.grid_step_rad
    if not step or step <= 0.0:
        return
    sep = min_separation_angle(cfg.swarm.min_separation_m, d_sep_m)
    if not math.isfinite(sep) or step * GRID_PER_SEPARATION >= sep:
        return
    key = step_key(c.raw.get("design"))
    n = int(round(2.0 * math.pi / step))
    raise c.error(f"step {step / DEG:.4g} deg makes {n:,} candidate angles, "
                  f"{sep / step:.0f} of them inside the {sep / DEG:.4g} deg that "
                  f"swarm.min_separation_km = {cfg.swarm.min_separation_m / 1e3:g} allows "
                  f"on a {d_sep_m / 1e3:.4g} km ring; use a step of at least "
                  f"{sep / GRID_PER_SEPARATION / DEG:.3g} deg", key)


def check_pointing(c, eta_rad: float, altitude_m: float) -> None:
    """Warn when a 3-sigma pointing dispersion is larger than the camera's half angle."""
    cfg = c.config
    kind = KINDS[cfg.kind]
    if not (kind.samples or kind.designs):
        return
    mc = cfg.monte_carlo
    mis = getattr(mc, "sigma_misalignment_rad", 0.0) or 0.0
    if N_SIGMA * mis > eta_rad:
        warn_field("monte_carlo.sigma_misalignment_deg",
                   f"{N_SIGMA:g} sigma = {N_SIGMA * mis / DEG:.4g} deg is larger than the camera's "
                   f"half field of view {eta_rad / DEG:.4g} deg: most samples will miss the body")
    pos = getattr(mc, "sigma_position_m", 0.0) or 0.0
    foot = altitude_m * math.tan(eta_rad)
    if N_SIGMA * pos > foot:
        warn_field("monte_carlo.sigma_position_m",
                   f"{N_SIGMA:g} sigma = {N_SIGMA * pos:.4g} m is larger than the footprint "
                   f"radius {foot:.4g} m (altitude {altitude_m / 1e3:.4g} km x tan of the half "
                   f"field of view {eta_rad / DEG:.4g} deg): most samples will miss the body")
