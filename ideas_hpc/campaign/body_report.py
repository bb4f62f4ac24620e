"""``ideas-hpc body FILE``: what the tool will use of a shape model (issue 32).

Prints the mesh's extent, volume, implied density for the given mass, centre of
mass against the origin, principal axes, and the degree-2 coefficients of a
constant-density body of that shape in the project's convention (unnormalised
C20, C22 times R_ref^2, km^2; :mod:`ideas_hpc.body.mass_properties`), which a
``[body.params]`` table without ``c20_km2``/``c22_km2`` uses as its default.
The checks of :mod:`ideas_hpc.campaign.body_checks` that need only the body
(density, centre of mass) run too: the report is printed, then the first
problem as one error line naming the option (exit 2).
"""

from __future__ import annotations

import math

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.units import DEG, KM


def add_body_command(sub) -> None:
    p = sub.add_parser("body", help="print what a shape model gives: size, volume, density, "
                                    "centre of mass, principal axes, C20/C22",
                       description="Read a shape model (.tab, .bds DSK, OBJ/PLY/STL/OFF, or a "
                                   "built-in name) and print what a campaign will use, with the "
                                   "constant-density C20/C22 (unnormalised, times R_ref^2, km^2, "
                                   "frame of the mesh about its centre of mass) as TOML lines for "
                                   "[body.params]. Refuses (exit 2) an implied density outside "
                                   "100-10,000 kg/m^3 and a centre of mass more than 5 % of the "
                                   "mean radius from the mesh origin.")
    p.add_argument("file", help="shape file or built-in body name")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--mass-kg", type=float, default=None, help="body mass, kg")
    g.add_argument("--gm-km3-s2", type=float, default=None,
                   help="gravitational parameter G M, km^3/s^2")
    p.add_argument("--length-unit", choices=("km", "m"), default="km",
                   help="length unit of an OBJ/PLY/STL/OFF mesh (default km; .tab and DSK are km)")
    p.add_argument("--data-path", default=None, help="folder searched for built-in shape models")
    p.set_defaults(handler=_cmd_body)


def _mu(args, body):
    from ideas_hpc.base.constants import G

    if args.mass_kg is not None:
        if not args.mass_kg > 0:
            raise InputError(f"must be > 0, got {args.mass_kg:g}", field="--mass-kg")
        return args.mass_kg * G, "--mass-kg"
    if args.gm_km3_s2 is not None:
        if not args.gm_km3_s2 > 0:
            raise InputError(f"must be > 0, got {args.gm_km3_s2:g}", field="--gm-km3-s2")
        return args.gm_km3_s2 * KM ** 3, "--gm-km3-s2"
    if body.params is not None:
        return body.params.mu, f"body {body.params.name} parameters"
    return None, None


def body_lines(body, mu) -> list[str]:
    """The report of :func:`_cmd_body` for a loaded body and ``mu`` (m^3/s^2 or None)."""
    from ideas_hpc.body.mass_properties import implied_density, mean_radius
    from ideas_hpc.base.constants import G

    s = body.shape
    p = s.mass_properties
    ex = p.extent_T_m / KM
    com = p.com_T_m / KM
    out = [f"shape: {s.summary()}",
           f"extent (x, y, z): {ex[0]:.4g} x {ex[1]:.4g} x {ex[2]:.4g} km "
           "(lengths as read: .tab and DSK in km, other meshes in --length-unit)",
           f"volume: {p.volume_m3 / KM ** 3:.6g} km^3, mean (equal-volume) radius "
           f"{mean_radius(p.volume_m3) / KM:.4g} km, R_av (R_max + R_min)/2 {s.r_av / KM:.4g} km"]
    if mu is None:
        out.append("density: give --mass-kg or --gm-km3-s2 to check it")
    else:
        out.append(f"mass: {mu / G:.6g} kg (GM {mu / KM ** 3:.6g} km^3/s^2), implied density "
                   f"{implied_density(mu, p.volume_m3):.4g} kg/m^3")
    out.append(f"centre of mass (constant density): ({com[0]:.4g}, {com[1]:.4g}, {com[2]:.4g}) "
               f"km, {np.linalg.norm(com):.4g} km from the mesh origin "
               f"({100 * np.linalg.norm(p.com_T_m) / mean_radius(p.volume_m3):.3g} % of the mean "
               "radius; frame T puts its origin there)")
    out.append("principal axes (columns in mesh frame T, increasing moment of inertia):")
    for k, name in enumerate(("long", "middle", "short")):
        ax = p.principal_T[:, k]
        out.append(f"  {name:<6} ({ax[0]: .4f}, {ax[1]: .4f}, {ax[2]: .4f})  "
                   f"I/M = {p.principal_moments_m2[k] / KM ** 2:.4g} km^2")
    distinct = np.min(np.diff(p.principal_moments_m2)) > 1e-3 * p.principal_moments_m2[-1]
    tilt = f"{p.axes_tilt_rad / DEG:.3g} deg" if distinct else "undefined (equal moments)"
    out.append(f"principal axes against T: largest tilt {tilt}; the degree-2 model keeps C20 "
               "and C22 of frame T only")
    out.append("C20/C22 of a constant-density body of this shape: unnormalised coefficients "
               "times R_ref^2, about the centre of mass in frame T (SPEC section 4: "
               "U2 = mu/r^3 [C20 (1 - 1.5 cos^2 delta) + 3 C22 cos^2 delta cos 2 lambda]); "
               "the default of a [body.params] table that gives neither:")
    out.append(f"  c20_km2 = {p.c20_m2 / KM ** 2:.6g}")
    out.append(f"  c22_km2 = {p.c22_m2 / KM ** 2:.6g}")
    if not math.isfinite(p.volume_m3) or p.volume_m3 <= 0:
        out.append("volume is not positive: the mesh is not a closed outward surface")
    return out


def _cmd_body(args) -> int:
    from ideas_hpc.body.bodies import load_body
    from ideas_hpc.body.mass_properties import (com_problem, density_problem, implied_density,
                                                mean_radius)

    try:
        body = load_body(args.file, data_path=args.data_path, length_unit=args.length_unit)
    except InputError as exc:
        if exc.field in ("body", None) and exc.file is None:
            raise InputError(exc.message, field="FILE") from None
        raise
    mu, source = _mu(args, body)
    print("\n".join(body_lines(body, mu)))
    p = body.shape.mass_properties
    if mu is not None:
        problem = density_problem(implied_density(mu, p.volume_m3))
        if problem:
            raise InputError(f"{problem} (--length-unit {args.length_unit}, mass from {source})",
                             field="--length-unit")
    problem = com_problem(p, mean_radius(p.volume_m3))
    if problem:
        raise InputError(problem, field="FILE")
    return 0
