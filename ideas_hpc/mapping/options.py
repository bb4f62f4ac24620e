"""Coverage options: how a vertex counts as observed, and the science requirement.

The ``[coverage]`` table of a campaign (user units) becomes a frozen
:class:`CoverageOptions` (SI) here; :mod:`ideas_hpc.mapping.coverage` applies them
to the kernels. Paper mode is the default: none of the strict options or requirements
set, and the stores hold exactly what they held before issue 14.

Requirement keys (issue 14): a vertex is *mapped* when one observation meets
every per-image limit that is set (``require_lit``, ``max_resolution_m``,
``max_emission_deg``, ``max_incidence_deg``, ``max_phase_deg``) and, with
``require_stereo``, two such observations form a stereo pair with a
convergence angle in ``[stereo_min_deg, stereo_max_deg]`` (see
:mod:`ideas_hpc.core.mapping.quality`). With a requirement set, ``coverage`` is the
mapped area fraction and ``coverage_seen`` the plain observed fraction.

Stereo defaults, 10-40 deg: the convergence angle between two lines of sight
must be large enough to give a height signal above the matching noise and
small enough that the two images still match (perspective and, for
stereophotoclinometry, illumination change). The NASA Ames Stereo Pipeline's
guidelines for selecting stereo pairs (docs, "Guidelines for selecting stereo
pairs") call 10-60 deg "likely reasonable", citing Becker et al. (2015),
"Criteria for automated identification of stereo image pairs", LPSC 46,
abstract 2703 (bibcode 2015LPI....46.2703B). We keep the lower bound and take
40 deg as the upper one, the conservative end of that range for matching
across the large perspective changes of a close flyby; for SPC see Gaskell et
al. (2008), Meteoritics & Planetary Science 43, 1049. Both bounds are settable
(``stereo_min_deg``, ``stereo_max_deg``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import Field, number, validate
from ideas_hpc.base.instrument import APERTURE, WAVELENGTH
from ideas_hpc.base.units import CM, DEG, MM, UM

_MODES = ("paper", "exact")
_BOOLS = ("occlusion", "illumination", "quality", "require_lit", "require_stereo")
_ANGLES = ("max_emission_rad", "max_incidence_rad", "max_phase_rad")


@dataclass(frozen=True)
class CoverageOptions:
    """How vertices are judged observed (SPEC section 6) and mapped (issue 14). All SI.

    Attributes
    ----------
    mode : {'paper', 'exact'}
        Culling test: paper ``r . n >= 0`` or exact ``(r - p) . n > 0``.
    occlusion : bool
        Self-occlusion: the segment vertex -> spacecraft crosses no face.
    illumination : bool
        Vertex lit by the Sun (``n . s > 0``) and not shadowed; needs ``sun_T``.
    min_elevation_rad : float or None
        Minimum elevation of the spacecraft above the local horizontal, rad.
    max_ground_resolution_m : float or None
        Largest ground sample ``lambda * range / D`` accepted, m.
    wavelength_m, aperture_m : float
        lambda (m) and D (m) for the ground resolution.
    pixel_pitch_m, focal_length_m : float or None
        Detector pixel pitch and focal length, m; when both are set the
        quality pass uses ``pitch / focal length`` instead of ``lambda / D``.
    quality : bool
        Compute the per-vertex quality variables (implied by any requirement).
    require_lit : bool
    max_resolution_m : float or None
        Largest effective ground sample ``rho * range / cos(emission)``, m.
    max_emission_rad, max_incidence_rad, max_phase_rad : float or None
        rad.
    require_stereo : bool
    stereo_min_rad, stereo_max_rad : float
        Convergence angle range of a stereo pair, rad (default 10-40 deg).
    """

    mode: str = "paper"
    occlusion: bool = False
    illumination: bool = False
    min_elevation_rad: float | None = None
    max_ground_resolution_m: float | None = None
    wavelength_m: float = WAVELENGTH
    aperture_m: float = APERTURE
    pixel_pitch_m: float | None = None
    focal_length_m: float | None = None
    quality: bool = False
    require_lit: bool = False
    max_resolution_m: float | None = None
    max_emission_rad: float | None = None
    max_incidence_rad: float | None = None
    max_phase_rad: float | None = None
    require_stereo: bool = False
    stereo_min_rad: float = math.radians(10.0)
    stereo_max_rad: float = math.radians(40.0)

    def __post_init__(self):
        if self.mode not in _MODES:
            raise InputError(f"must be one of {_MODES}, got {self.mode!r}", field="mode")
        for name in _BOOLS:
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise InputError(f"must be true or false, got {getattr(self, name)!r}",
                                 field=name)
        if self.min_elevation_rad is not None:
            e = _finite(self.min_elevation_rad, "min_elevation_rad")
            if not 0.0 <= e < math.pi / 2:
                raise InputError(f"must be in [0, 90) deg, got {math.degrees(e):g} deg",
                                 field="min_elevation_rad")
        for name in ("max_ground_resolution_m", "max_resolution_m", "pixel_pitch_m",
                     "focal_length_m"):
            if getattr(self, name) is not None and _finite(getattr(self, name), name) <= 0.0:
                raise InputError("must be > 0", field=name)
        if (self.pixel_pitch_m is None) != (self.focal_length_m is None):
            raise InputError("pixel_pitch and focal_length go together",
                             field="pixel_pitch_m" if self.pixel_pitch_m is None
                             else "focal_length_m")
        for name in ("wavelength_m", "aperture_m"):
            if _finite(getattr(self, name), name) <= 0.0:
                raise InputError(f"must be > 0, got {getattr(self, name)!r}", field=name)
        for name in _ANGLES:
            v = getattr(self, name)
            if v is not None and not 0.0 < _finite(v, name) <= math.pi:
                raise InputError(f"must be in (0, 180] deg, got {math.degrees(v):g} deg",
                                 field=name)
        lo = _finite(self.stereo_min_rad, "stereo_min_rad")
        hi = _finite(self.stereo_max_rad, "stereo_max_rad")
        if not 0.0 < lo < hi <= math.pi:
            raise InputError(f"need 0 < stereo_min < stereo_max <= 180 deg, got "
                             f"{math.degrees(lo):g}, {math.degrees(hi):g} deg",
                             field="stereo_max_rad" if hi > math.pi else "stereo_min_rad")

    @property
    def strict(self) -> bool:
        """True when any option beyond the paper's culling + clipping is on."""
        return (self.occlusion or self.illumination or self.min_elevation_rad is not None
                or self.max_ground_resolution_m is not None)

    @property
    def requirement(self) -> bool:
        """True when a coverage requirement (issue 14) is set."""
        return (self.require_lit or self.require_stereo
                or any(getattr(self, n) is not None
                       for n in ("max_resolution_m",) + _ANGLES))

    @property
    def wants_quality(self) -> bool:
        """Run the quality pass (asked for, or needed by a requirement)."""
        return bool(self.quality or self.requirement)

    @property
    def needs_sun(self) -> bool:
        return bool(self.illumination or self.wants_quality)

    @property
    def max_range(self) -> float:
        """Largest range allowed by the ground resolution, ``X D / lambda`` (m)."""
        if self.max_ground_resolution_m is None:
            return math.inf
        return self.max_ground_resolution_m * self.aperture_m / self.wavelength_m

    @property
    def rho(self) -> float:
        """Angular ground sample, rad: ``pitch / focal length`` or ``lambda / D``."""
        if self.pixel_pitch_m is not None:
            return self.pixel_pitch_m / self.focal_length_m
        return self.wavelength_m / self.aperture_m

    @property
    def limits(self) -> np.ndarray:
        """``[X_max, e_max, i_max, g_max, s_min, s_max]`` for the quality kernel (inf: none)."""
        v = [self.max_resolution_m] + [getattr(self, n) for n in _ANGLES]
        return np.array([math.inf if x is None else float(x) for x in v]
                        + [float(self.stereo_min_rad), float(self.stereo_max_rad)])


def _finite(value, field: str) -> float:
    return number(value, field)


def _opt(kind: str, si: str, to_si: float = 1.0, **kw) -> Field:
    # None: not given, so CoverageOptions keeps its own default (defaults live there only)
    return Field(kind, None, nullable=True, si=si, to_si=to_si, **kw)


#: The ``[coverage]`` table: file keys in user units -> CoverageOptions fields (SI).
COVERAGE_SCHEMA = {
    "mode": _opt("str", "mode", choices=_MODES),
    "occlusion": _opt("bool", "occlusion"),
    "illumination": _opt("bool", "illumination"),
    "min_elevation_deg": _opt("float", "min_elevation_rad", DEG),
    "max_ground_resolution_m": _opt("float", "max_ground_resolution_m"),
    "wavelength_um": _opt("float", "wavelength_m", UM),
    "aperture_cm": _opt("float", "aperture_m", CM),
    "pixel_pitch_um": _opt("float", "pixel_pitch_m", UM),
    "focal_length_mm": _opt("float", "focal_length_m", MM),
    "quality": _opt("bool", "quality"),
    "require_lit": _opt("bool", "require_lit"),
    "max_resolution_m": _opt("float", "max_resolution_m"),
    "max_emission_deg": _opt("float", "max_emission_rad", DEG),
    "max_incidence_deg": _opt("float", "max_incidence_rad", DEG),
    "max_phase_deg": _opt("float", "max_phase_rad", DEG),
    "require_stereo": _opt("bool", "require_stereo"),
    "stereo_min_deg": _opt("float", "stereo_min_rad", DEG),
    "stereo_max_deg": _opt("float", "stereo_max_rad", DEG),
}


def coverage_options_from_config(table: dict, prefix: str = "coverage.") -> CoverageOptions:
    """Build :class:`CoverageOptions` from a config table in user units.

    Keys: ``mode`` ('paper' | 'exact'), ``occlusion``, ``illumination`` (bool),
    ``min_elevation_deg``, ``max_ground_resolution_m``, ``wavelength_um``,
    ``aperture_cm``, ``pixel_pitch_um``, ``focal_length_mm``, and the issue 14
    quality pass and requirement: ``quality``, ``require_lit``,
    ``require_stereo`` (bool), ``max_resolution_m``, ``max_emission_deg``,
    ``max_incidence_deg``, ``max_phase_deg``, ``stereo_min_deg``,
    ``stereo_max_deg``. Unknown keys and wrong types raise :class:`InputError`
    naming ``prefix + key``; a value :class:`CoverageOptions` refuses names its
    field (``min_elevation_rad``), which the campaign layer maps to the file's key
    (:data:`ideas_hpc.campaign.schema.model_fields.COVERAGE_FIELDS`).
    """
    values = validate(table, COVERAGE_SCHEMA, prefix)   # one mechanism for every table
    given = table or {}
    return CoverageOptions(**{COVERAGE_SCHEMA[k].si_name(k): values[k]
                              for k in COVERAGE_SCHEMA if k in given})


@dataclass(frozen=True)
class Frustum:
    """The camera's view: square field-of-view half angle ``eta_rad`` in (0, pi/2)
    and the clipping distances ``near_m`` < ``far_m``."""

    eta_rad: float
    near_m: float
    far_m: float


def frustum_of(values, field: str = "frustum") -> tuple:
    """``(eta_rad, near_m, far_m)`` of a :class:`Frustum` given alone, or of the three
    numbers given in its place (the older positional call)."""
    if len(values) == 1 and isinstance(values[0], Frustum):
        f = values[0]
        return f.eta_rad, f.near_m, f.far_m
    if len(values) == 3:
        return tuple(values)
    raise InputError(f"give a Frustum or eta, near, far; got {len(values)} values", field=field)
