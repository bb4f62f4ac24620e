"""Instrument and flyby sizing (SPEC section 2; paper Tables 3 and 4).

Given the ground resolution X, aperture D, wavelength lambda and the minimum
elevation angle eps::

    h          = X D / lambda                 flyby altitude (diffraction limit)
    d_sep      = R_av + h                     ring radius
    sin(rho)   = R_av / d_sep                 angular radius of the body
    sin(eta_N) = sin(rho) cos(eps)            nadir half cone angle
    r_f        = h + 2 R_av                   far field
    r_n        = 0.1 mm                       near field
    eta_FOV    = theta_max = eta_N / 2        FoV sweeping

The paper's printed digits come from R_max = 17.670 km and R_min = 3.222 km
(``R_av = 10.446 km``); eros001708 gives R_av = 10.434 km, which changes the 4th
digit. The paper's sweep angle 1.9138 deg is consistent with R_av = 10.447 km
(its Table 1 rounding); from 10.446 km it is 1.9137 deg.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import number
from ideas_hpc.base.instrument import (APERTURE, GROUND_RESOLUTION,  # noqa: F401 (public here too)
                                  INSTRUMENT_DEFAULTS, MIN_ELEVATION, NEAR_FIELD, WAVELENGTH)
from ideas_hpc.base.units import DEG, KM


@dataclass(frozen=True)
class Sizing:
    """Result of :func:`size_flyby`; lengths in m, angles in rad."""

    r_av: float
    altitude: float
    d_sep: float
    rho: float
    eta_nadir: float
    far: float
    near: float
    eta_fov: float
    theta_max: float
    ground_resolution: float
    aperture: float
    wavelength: float
    min_elevation: float

    def as_dict(self) -> dict:
        return asdict(self)

    def table(self) -> list[tuple[str, float, str]]:
        """Rows ``(quantity, value, unit)`` in km and deg, in the paper's order."""
        return [
            ("mean radius R_av", self.r_av / KM, "km"),
            ("flyby altitude h", self.altitude / KM, "km"),
            ("ring radius d_sep", self.d_sep / KM, "km"),
            ("angular radius rho", self.rho / DEG, "deg"),
            ("nadir half cone eta_N", self.eta_nadir / DEG, "deg"),
            ("far field r_f", self.far / KM, "km"),
            ("near field r_n", self.near * 1e3, "mm"),
            ("FoV half cone eta_FOV", self.eta_fov / DEG, "deg"),
            ("max sweep angle theta_max", self.theta_max / DEG, "deg"),
        ]


def size_flyby(*, r_av: float | None = None, r_max: float | None = None,
               r_min: float | None = None, ground_resolution: float = GROUND_RESOLUTION,
               aperture: float = APERTURE, wavelength: float = WAVELENGTH,
               min_elevation: float = MIN_ELEVATION, near: float = NEAR_FIELD) -> Sizing:
    """Size the instrument and the ring flyby (SPEC section 2). All inputs SI.

    Give either ``r_av`` or both ``r_max`` and ``r_min`` (then
    ``r_av = (r_max + r_min) / 2`` as in the paper's Table 1).

    Raises
    ------
    InputError
        Non-positive radius, resolution, aperture or wavelength; an elevation
        outside [0, 90) deg.
    """
    if r_av is None:
        if r_max is None or r_min is None:
            raise InputError("give r_av, or both r_max and r_min", field="r_av")
        r_max = number(r_max, "r_max", lo=0.0, lo_open=True)
        r_min = number(r_min, "r_min", lo=0.0, lo_open=True)
        if r_min > r_max:
            raise InputError(f"r_min ({r_min:g} m) exceeds r_max ({r_max:g} m)", field="r_min")
        r_av = 0.5 * (r_max + r_min)
    r_av = number(r_av, "r_av", lo=0.0, lo_open=True)
    x = number(ground_resolution, "ground_resolution", lo=0.0, lo_open=True)
    d = number(aperture, "aperture", lo=0.0, lo_open=True)
    lam = number(wavelength, "wavelength", lo=0.0, lo_open=True)
    near = number(near, "near", lo=0.0, lo_open=True)
    eps = float(min_elevation)
    if not math.isfinite(eps) or eps < 0.0 or eps >= 0.5 * math.pi:
        raise InputError(f"must be in [0, 90) deg, got {eps / DEG:g} deg", field="min_elevation")
    h = x * d / lam
    d_sep = r_av + h
    rho = math.asin(r_av / d_sep)
    eta_n = math.asin(math.sin(rho) * math.cos(eps))
    far = h + 2.0 * r_av
    if near >= far:
        raise InputError(f"near field {near:g} m must be below the far field {far:g} m",
                         field="near")
    return Sizing(r_av=r_av, altitude=h, d_sep=d_sep, rho=rho, eta_nadir=eta_n, far=far,
                  near=near, eta_fov=0.5 * eta_n, theta_max=0.5 * eta_n,
                  ground_resolution=x, aperture=d, wavelength=lam, min_elevation=eps)


def size_for_body(body, **instrument) -> Sizing:
    """:func:`size_flyby` from a body's shape (R_max and R_min of its vertices)."""
    return size_flyby(r_max=body.shape.r_max, r_min=body.shape.r_min, **instrument)


#: The paper's inputs for its printed Tables 3 and 4 (R_max, R_min of Table 1).
PAPER_R_MAX = 17.670 * KM
PAPER_R_MIN = 3.222 * KM


def format_table(sizing: Sizing, title: str, reference: Sizing | None = None) -> str:
    """Plain-text table in km and deg, optionally beside a reference column."""
    rows = sizing.table()
    ref = reference.table() if reference is not None else None
    lines = [title]
    head = f"  {'quantity':<28}{'value':>14}  unit"
    if ref:
        head += f"{'paper inputs':>16}"
    lines.append(head)
    for i, (name, val, unit) in enumerate(rows):
        s = f"  {name:<28}{val:>14.4f}  {unit:<4}"
        if ref:
            s += f"{ref[i][1]:>16.4f}"
        lines.append(s)
    return "\n".join(lines)
