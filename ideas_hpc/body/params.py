"""Physical parameter sets of target bodies (paper Table 1, SPEC section 1).

Sets are written in the units people quote (kg, h, km^2, AU, deg) and
converted once, here, to SI. Named presets live in :data:`PRESETS`; a user set
comes from a TOML table with the same keys (see :func:`params_from_mapping`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from ideas_hpc.base.constants import AU, G
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import number
from ideas_hpc.base.units import DEG, HOUR, KM



@dataclass(frozen=True)
class PhysicalParams:
    """Physical parameters of a target body, SI units.

    Attributes
    ----------
    name : str
    mu : float
        Gravitational parameter G M, m^3/s^2.
    spin_period : float
        Sidereal rotation period about +z of frame T, s.
    c20, c22 : float
        Unnormalised degree-2 coefficients times R_ref^2, m^2 (SPEC section 4).
    orbit_a : float
        Heliocentric semi-major axis, m.
    orbit_e, orbit_i, orbit_raan, orbit_argp, orbit_nu : float
        Eccentricity and angles (rad) of the heliocentric orbit at t0.
    pole_ra, pole_dec : float or None
        Spin pole in the inertial (ecliptic) frame, rad; None means the
        orbit normal is taken as the pole (SPEC section 4).
    prime_meridian : float
        Rotation angle of frame T about the pole at t0, rad.
    """

    name: str
    mu: float
    spin_period: float
    c20: float
    c22: float
    orbit_a: float
    orbit_e: float
    orbit_i: float
    orbit_raan: float
    orbit_argp: float
    orbit_nu: float
    pole_ra: float | None = None
    pole_dec: float | None = None
    prime_meridian: float = 0.0

    @property
    def mass(self) -> float:
        """Mass in kg (``mu / G``)."""
        return self.mu / G

    @property
    def spin_rate(self) -> float:
        """Spin rate about +z of frame T, rad/s."""
        return 2.0 * math.pi / self.spin_period

    def as_dict(self) -> dict:
        return asdict(self)


# Keys of a user parameter table: name -> (SI factor, required, lower bound, open/closed)
_KEYS = {
    "mass_kg": 1.0,
    "gm_km3_s2": KM ** 3,
    "spin_period_h": HOUR,
    "c20_km2": KM * KM,
    "c22_km2": KM * KM,
    "a_au": AU,
    "e": 1.0,
    "i_deg": DEG,
    "raan_deg": DEG,
    "argp_deg": DEG,
    "nu_deg": DEG,
    "pole_ra_deg": DEG,
    "pole_dec_deg": DEG,
    "prime_meridian_deg": DEG,
}


def _num(table, key, prefix):
    return number(table[key], f"{prefix}{key}")


def params_from_mapping(table: dict, *, name: str = "custom", prefix: str = "") -> PhysicalParams:
    """Build a parameter set from user units (a TOML table).

    Keys: ``mass_kg`` or ``gm_km3_s2`` (one of them), ``spin_period_h``,
    ``c20_km2``, ``c22_km2`` (default 0), ``a_au``, ``e``, ``i_deg``, ``raan_deg``,
    ``argp_deg``, ``nu_deg`` (angles default 0), optional ``pole_ra_deg`` and
    ``pole_dec_deg`` (both or neither), ``prime_meridian_deg`` (default 0).
    ``prefix`` is prepended to field names in errors (``body.params.``).
    """
    unknown = sorted(set(table) - set(_KEYS) - {"name"})
    if unknown:
        raise InputError(f"unknown key {unknown[0]!r}; allowed: {', '.join(sorted(_KEYS))}",
                         field=f"{prefix}{unknown[0]}")
    vals = {k: _num(table, k, prefix) for k in table if k in _KEYS}
    if ("mass_kg" in vals) == ("gm_km3_s2" in vals):
        raise InputError("give exactly one of mass_kg and gm_km3_s2", field=f"{prefix}mass_kg")
    mu = vals["mass_kg"] * G if "mass_kg" in vals else vals["gm_km3_s2"] * KM ** 3
    if mu <= 0:
        raise InputError("must be > 0", field=f"{prefix}{'mass_kg' if 'mass_kg' in vals else 'gm_km3_s2'}")
    for req in ("spin_period_h", "a_au", "e"):
        if req not in vals:
            raise InputError("is required", field=f"{prefix}{req}")
    if vals["spin_period_h"] <= 0:
        raise InputError("must be > 0", field=f"{prefix}spin_period_h")
    if vals["a_au"] <= 0:
        raise InputError("must be > 0", field=f"{prefix}a_au")
    if not 0.0 <= vals["e"] < 1.0:
        raise InputError("must be in [0, 1) (elliptic orbit)", field=f"{prefix}e")
    if ("pole_ra_deg" in vals) != ("pole_dec_deg" in vals):
        raise InputError("give both pole_ra_deg and pole_dec_deg, or neither",
                         field=f"{prefix}pole_dec_deg")
    if "pole_dec_deg" in vals and abs(vals["pole_dec_deg"]) > 90.0:
        raise InputError("must be in [-90, 90] deg", field=f"{prefix}pole_dec_deg")
    g = lambda k, d=0.0: vals.get(k, d) * _KEYS[k]  # noqa: E731
    return PhysicalParams(
        name=str(table.get("name", name)), mu=mu, spin_period=g("spin_period_h"),
        c20=g("c20_km2"), c22=g("c22_km2"), orbit_a=g("a_au"), orbit_e=vals["e"],
        orbit_i=g("i_deg"), orbit_raan=g("raan_deg"), orbit_argp=g("argp_deg"),
        orbit_nu=g("nu_deg"),
        pole_ra=g("pole_ra_deg") if "pole_ra_deg" in vals else None,
        pole_dec=g("pole_dec_deg") if "pole_dec_deg" in vals else None,
        prime_meridian=g("prime_meridian_deg"))


#: Paper Table 1 (433 Eros).
EROS_TABLE1 = {
    "name": "eros", "mass_kg": 6.689e15, "spin_period_h": 5.270,
    "c20_km2": -30.010, "c22_km2": 14.382, "a_au": 1.457, "e": 0.222,
    "i_deg": 10.828, "raan_deg": 304.320, "argp_deg": 178.820, "nu_deg": 0.0,
}

PRESETS = {"eros": params_from_mapping(EROS_TABLE1)}


def get_params(name: str) -> PhysicalParams:
    """A named preset (``eros``)."""
    key = name.lower()
    if key not in PRESETS:
        raise InputError(f"unknown parameter set {name!r}; known: {', '.join(sorted(PRESETS))}",
                         field="body.params")
    return PRESETS[key]
