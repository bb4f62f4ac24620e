"""Spacecraft model: rigid body with three reaction wheels (SPEC section 5)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import Field, number, validate

def _opt(kind: str, doc: str, **kw) -> Field:
    # None: not given, the SpacecraftModel default applies (defaults live there only)
    return Field(kind, None, nullable=True, doc=doc, **kw)


#: The ``[spacecraft]`` table (SI) -> :class:`SpacecraftModel` fields (``si``); ranges are
#: checked by :func:`validate_spacecraft`.
SPACECRAFT_SCHEMA = {
    "mass": _opt("float", "kg", si="mass_kg"),
    "size": _opt("floats", "3 lengths, m", length=3, si="size_m"),
    "wheel_mass": _opt("float", "kg", si="wheel_mass_kg"),
    "wheel_radius": _opt("float", "m", si="wheel_radius_m"),
    "u_max": _opt("float", "N m", si="u_max_N_m"),
    "h_max": _opt("float", "N m s", si="h_max_N_m_s"),
    "inertia": _opt("any", "3 principal moments or a diagonal 3x3 matrix, kg m^2",
                    si="inertia_kg_m2"),
}


@dataclass(frozen=True)
class SpacecraftModel:
    """Rigid spacecraft with three reaction wheels on its principal axes (SPEC section 5).

    SI units, the unit in the name; the ``[spacecraft]`` keys drop it
    (:data:`ideas_hpc.campaign.schema.model_fields.SPACECRAFT_FIELDS`).

    Attributes
    ----------
    mass_kg : float
        Hub mass, kg (4).
    size_m : tuple of 3 floats
        Box edges along body x, y, z, m ((0.1, 0.1, 0.3): z along the 30 cm side).
    wheel_mass_kg : float
        kg (0.24).
    wheel_radius_m : float
        m (0.029).
    u_max_N_m : float
        Wheel torque limit, N m (0.007).
    h_max_N_m_s : float
        Wheel momentum limit ``|J_s Omega|``, N m s (0.05).
    inertia_kg_m2 : tuple of 3 floats or None
        Hub principal moments, kg m^2; ``None`` means the uniform box.
    """

    mass_kg: float = 4.0
    size_m: tuple = (0.1, 0.1, 0.3)
    wheel_mass_kg: float = 0.24
    wheel_radius_m: float = 0.029
    u_max_N_m: float = 0.007
    h_max_N_m_s: float = 0.05
    inertia_kg_m2: tuple | None = None

    @property
    def inertia_hub(self) -> np.ndarray:
        """Hub principal moments, kg m^2: uniform box ``m/12 (b^2 + c^2)`` unless given."""
        if self.inertia_kg_m2 is not None:
            return np.array(self.inertia_kg_m2, dtype=np.float64)
        a, b, c = self.size_m
        m = self.mass_kg
        return np.array([m / 12 * (b * b + c * c), m / 12 * (a * a + c * c),
                         m / 12 * (a * a + b * b)])

    @property
    def wheel_spin_inertia(self) -> float:
        """``J_s = m r^2 / 2`` (uniform disc), kg m^2."""
        return 0.5 * self.wheel_mass_kg * self.wheel_radius_m ** 2

    @property
    def wheel_transverse_inertia(self) -> float:
        """``J_t = m r^2 / 4`` (thin uniform disc about a diameter), kg m^2."""
        return 0.25 * self.wheel_mass_kg * self.wheel_radius_m ** 2

    @property
    def J_s(self) -> np.ndarray:
        """Wheel spin inertias (3,), kg m^2."""
        return np.full(3, self.wheel_spin_inertia)

    @property
    def inertia_rw(self) -> np.ndarray:
        """Principal moments of ``[I_RW]`` (hub plus wheel transverse inertia), kg m^2.

        Each axis sees the transverse inertia of the two wheels not on it
        (wheels at the centre of mass; S&J eq. 4.140 with ``[G_s] = I``).
        """
        return self.inertia_hub + 2.0 * self.wheel_transverse_inertia


def validate_spacecraft(sc: SpacecraftModel) -> SpacecraftModel:
    """Check a :class:`SpacecraftModel`; raise :class:`InputError` naming its field
    (``mass_kg``; the campaign layer maps it to the file's key)."""
    number(sc.mass_kg, "mass_kg", lo=0.0, lo_open=True)
    number(sc.wheel_mass_kg, "wheel_mass_kg", lo=0.0)
    number(sc.wheel_radius_m, "wheel_radius_m", lo=0.0, lo_open=True)
    if sc.wheel_mass_kg == 0.0:
        raise InputError("wheel mass must be positive (J_s = m r^2 / 2 > 0)",
                         field="wheel_mass_kg")
    number(sc.u_max_N_m, "u_max_N_m", lo=0.0)
    number(sc.h_max_N_m_s, "h_max_N_m_s", lo=0.0)
    if sc.inertia_kg_m2 is None:
        size = np.asarray(sc.size_m, dtype=float)
        if size.shape != (3,) or not np.all(np.isfinite(size)) or np.any(size <= 0):
            raise InputError(f"must be three positive lengths in m, got {sc.size_m!r}",
                             field="size_m")
    else:
        i = np.asarray(sc.inertia_kg_m2, dtype=float)
        if i.shape != (3,) or not np.all(np.isfinite(i)) or np.any(i <= 0.0):
            raise InputError(f"inertia is not positive definite: principal moments "
                             f"{sc.inertia_kg_m2!r} (kg m^2) must all be > 0",
                             field="inertia_kg_m2")
        s = np.sort(i)
        if s[0] + s[1] < s[2] * (1 - 1e-12):
            raise InputError(f"principal moments {sc.inertia_kg_m2!r} violate the triangle "
                             "inequality of a rigid body", field="inertia_kg_m2")
    return sc


def default_spacecraft() -> SpacecraftModel:
    """The paper's 4 kg, 30x10x10 cm spacecraft with Table 5 wheels."""
    return SpacecraftModel()


def spacecraft_from_config(table, prefix: str = "spacecraft.") -> SpacecraftModel:
    """Build a :class:`SpacecraftModel` from a config table (SI units).

    Keys (all optional, defaults of :func:`default_spacecraft`): ``mass`` (kg),
    ``size`` (3 lengths, m), ``wheel_mass`` (kg), ``wheel_radius`` (m),
    ``u_max`` (N m), ``h_max`` (N m s), ``inertia`` (3 principal moments or a
    3x3 matrix, kg m^2; a matrix must be diagonal because the wheels sit on the
    principal axes). Any other key is an error naming it (SRP mass and area
    live in ``[dynamics]``), as is a bad inertia matrix (``prefix + "inertia"``); a
    value :func:`validate_spacecraft` refuses names the :class:`SpacecraftModel`
    field, which the campaign layer maps to the file's key
    (:data:`ideas_hpc.campaign.schema.model_fields.SPACECRAFT_FIELDS`).
    """
    table = dict(table or {})
    values = validate(table, SPACECRAFT_SCHEMA, prefix)  # the one field mechanism
    kw = {SPACECRAFT_SCHEMA[k].si_name(k): (tuple(v) if k == "size" else v)
          for k, v in values.items() if v is not None and k != "inertia"}
    if "inertia" in table:
        try:
            m = np.asarray(table["inertia"], dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"must be numbers, got {table['inertia']!r}",
                             field=prefix + "inertia") from None
        if m.shape == (3, 3):
            if not np.all(np.isfinite(m)):
                raise InputError("must be finite", field=prefix + "inertia")
            if not np.allclose(m, m.T, rtol=0, atol=1e-12 * np.abs(m).max()):
                raise InputError("inertia matrix is not symmetric", field=prefix + "inertia")
            if np.linalg.eigvalsh(m).min() <= 0.0:
                raise InputError("inertia is not positive definite", field=prefix + "inertia")
            if np.abs(m - np.diag(np.diag(m))).max() > 1e-12 * np.abs(m).max():
                raise InputError("inertia must be diagonal: the body frame is the principal "
                                 "frame carrying the wheels", field=prefix + "inertia")
            m = np.diag(m)
        if m.shape != (3,):
            raise InputError(f"must be 3 principal moments or a 3x3 matrix, got shape "
                             f"{m.shape}", field=prefix + "inertia")
        kw["inertia_kg_m2"] = tuple(float(v) for v in m)
    return validate_spacecraft(SpacecraftModel(**kw))
