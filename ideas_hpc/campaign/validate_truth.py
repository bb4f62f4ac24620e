"""``ideas-hpc validate --truth-...``: a design's swarm flown at one given target (issue 42,
deliverable 7; SPEC 7f).

A design made under a target prior answers for the prior's worlds. A reader with another
idea of the target (a shape model from elsewhere, a lightcurve pole, a phase) asks what
the swarm does at *that* target. :func:`truth_world` builds that one world as a
:class:`~ideas_hpc.body.target_prior.TargetWorld` (shape in its own body frame ``T_w``:
origin at its centre of mass, +z the spin pole, +x the prime meridian; pole ``(alpha,
delta)`` J2000 equatorial, as the prior's; period; rotation angle ``W`` at closest
approach), and :func:`truth_setup` makes it the setup's "prior" (:class:`GivenTruth`:
every draw is that world). So every validation sample flies it through exactly the path
a drawn world takes (:func:`~ideas_hpc.flyby.target_world.drawn_world`): placed in the
nominal frame ``T0`` at closest approach by its pole and phase
(:func:`~ideas_hpc.flyby.target_world.placed_world`), ``mu`` scaled by its volume at the
nominal bulk density, C20/C22 its own; the navigation errors, continuous dispersions and
failures are still drawn per sample. Its vertex weights are its own
(:func:`~ideas_hpc.flyby.target_world.world_areas`: its vertex areas, or with a
``design.coverage_reference`` its reference area in this world).

The truth's mesh may have any topology: the rows are per vertex of the *flown* mesh, and
a validation needs only the flown rows and the flown areas (never the design's rows). The
period is recorded but, as for a drawn world, the flight frame keeps the nominal spin over
the short imaging window (:mod:`ideas_hpc.flyby.target_world`).

A design on a known body (no ``[target]`` prior) accepts a truth too: it is placed the same
way about the body's own pole and phase; a truth equal to the design's body gives the
ordinary validation's values (``tests/test_validate_truth.py``).

Several truths pool (:func:`~ideas_hpc.campaign.validate_store.pooled`): all their per-sample values as one sample, its mean
and the same betting bound as the validation
(:func:`~ideas_hpc.design.reliability_stats.lower_confidence_bound`), and the drawn successes
summed with their Wilson interval. The pooled P-hat estimates the mean over the truths
given (each weighted by its sample count); the bound treats the pooled values as
independent draws of that mixture.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.body.shape import Shape
from ideas_hpc.body.spin_prior import DCM_N_EQ, unit_from_angles
from ideas_hpc.body.target_prior import TargetWorld
from ideas_hpc.flyby.target_world import dcm_TN, t_tca_s

HOUR = 3600.0


@dataclass(frozen=True)
class GivenTruth:
    """A "prior" of one world: every draw is ``world`` (module docstring)."""

    world: TargetWorld
    name: str = "given truth"
    #: every draw is the same world: placed once per process
    #: (:func:`~ideas_hpc.flyby.target_world.drawn_world`)
    one_world = True

    def draw(self, seed: int, k: int, family: int = 0) -> TargetWorld:
        return self.world


@dataclass(frozen=True)
class TruthOptions:
    """What the command line gave (SI; None: the design's nominal value).

    ``shape``: a shape file (:func:`~ideas_hpc.body.formats.load_shape_file`, km unless the
    format says otherwise), a built-in body name, or ``ellipsoid:A,B,C`` (semi-axes, km).
    """

    shape: str | None = None
    pole_ra_dec_rad: tuple[float, float] | None = None
    period_s: float | None = None
    phase_rad: float | None = None

    @property
    def given(self) -> bool:
        return any(x is not None for x in dataclasses.astuple(self))


def truth_shape(spec: str, resolution: int = 3) -> Shape:
    """The truth's :class:`Shape` (m, its body frame) from a file, a built-in name or
    ``ellipsoid:A,B,C`` (km); a bad one is an input error naming ``--truth-shape``."""
    from ideas_hpc.body import analytic
    from ideas_hpc.body.formats import builtin_body, builtin_names, load_shape_file

    text = str(spec).strip()
    if text.lower().startswith("ellipsoid:"):
        return analytic.ellipsoid_mesh(*_axes_km(text), resolution, name="truth-ellipsoid")
    got = builtin_body(text)
    if got is not None and not Path(text).is_file():
        return got[1].load(None, resolution, None)[0]
    if not Path(text).is_file():
        raise InputError(f"{text!r} is no shape file, built-in body "
                         f"({', '.join(builtin_names())}) or ellipsoid:A,B,C (km)",
                         field="--truth-shape")
    try:
        return load_shape_file(text)
    except InputError as exc:
        raise InputError(f"{text}: {exc}", field="--truth-shape") from None


def _axes_km(text: str) -> list[float]:
    """The semi-axes (m) of ``ellipsoid:A,B,C`` (km)."""
    try:
        axes = [float(x) * 1e3 for x in text.split(":", 1)[1].split(",")]
    except ValueError:
        axes = []
    if len(axes) != 3 or not all(math.isfinite(a) and a > 0 for a in axes):
        raise InputError(f"ellipsoid:A,B,C needs three positive semi-axes in km, got "
                         f"{text!r}", field="--truth-shape")
    return axes


def parse_pole(text: str) -> tuple[float, float]:
    """``"RA,DEC"`` (deg, J2000 equatorial) to rad; RA in [0, 360), Dec in [-90, 90]."""
    try:
        ra, dec = (float(x) for x in str(text).split(","))
    except ValueError:
        raise InputError(f"needs RA,DEC in degrees, got {text!r}", field="--truth-pole") from None
    if not (0.0 <= ra < 360.0 and -90.0 <= dec <= 90.0):
        raise InputError(f"RA must be in [0, 360) and Dec in [-90, 90] deg, got {text!r}",
                         field="--truth-pole")
    return math.radians(ra), math.radians(dec)


def truth_options(shape=None, pole=None, period_h=None, phase_deg=None) -> TruthOptions:
    """The command line's truth options (strings or numbers as given) in SI, checked."""
    if period_h is not None and not (math.isfinite(float(period_h)) and float(period_h) > 0):
        raise InputError(f"must be > 0 h, got {period_h}", field="--truth-period-h")
    if phase_deg is not None and not math.isfinite(float(phase_deg)):
        raise InputError(f"must be finite, got {phase_deg}", field="--truth-phase-deg")
    return TruthOptions(shape=shape, pole_ra_dec_rad=None if pole is None else parse_pole(pole),
                        period_s=None if period_h is None else float(period_h) * HOUR,
                        phase_rad=None if phase_deg is None
                        else math.radians(float(phase_deg)) % (2.0 * math.pi))


def nominal_truth(setup) -> tuple[np.ndarray, float, float]:
    """``(pole_N, period_s, phase_tca_rad)`` of ``setup``'s nominal body: the values a
    truth option left out takes."""
    p = setup.body.require_params()
    pole_N = dcm_TN(p, None, 0.0)[2]          # +z of T in N
    phase = (p.prime_meridian + p.spin_rate * (setup.epoch_s + t_tca_s(setup))) % (2 * math.pi)
    return pole_N, float(p.spin_period), phase


def truth_world(setup, shape: Shape | None = None, *, pole_ra_dec_rad=None,
                period_s: float | None = None, phase_rad: float | None = None) -> TargetWorld:
    """The one world of a given truth (module docstring); what is None is the nominal's.

    ``shape`` in its body frame (origin at its centre of mass: not moved here, as a drawn
    world is not); ``pole_ra_dec_rad`` J2000 equatorial; ``phase_rad`` the rotation angle
    at closest approach.
    """
    pole0, period0, phase0 = nominal_truth(setup)
    shape = setup.body.shape if shape is None else shape
    pole_N = pole0 if pole_ra_dec_rad is None else DCM_N_EQ @ unit_from_angles(*pole_ra_dec_rad)
    d = 2.0 * (3.0 * shape.mass_properties.volume_m3 / (4.0 * math.pi)) ** (1.0 / 3.0)
    d0 = 2.0 * (3.0 * setup.body.shape.mass_properties.volume_m3 / (4.0 * math.pi)) ** (1 / 3)
    return TargetWorld(seed=-1, k=-1, family=-1, shape=shape, diameter_m=d, size_scale=d / d0,
                       star_centre_T_m=np.zeros(3), pole_N=np.asarray(pole_N, dtype=np.float64),
                       pole_mirrored=False,
                       spin_period_s=period0 if period_s is None else float(period_s),
                       phase_tca_rad=phase0 if phase_rad is None else float(phase_rad),
                       phase_uniform=False)


def truth_setup(setup, world: TargetWorld):
    """``setup`` whose every flight flies ``world`` (:class:`GivenTruth`)."""
    return dataclasses.replace(setup, target=GivenTruth(world))


def options_world(setup, opts: TruthOptions, resolution: int = 3) -> TargetWorld:
    """:func:`truth_world` of the command line's options."""
    shape = None if opts.shape is None else truth_shape(opts.shape, resolution)
    world = truth_world(setup, shape, pole_ra_dec_rad=opts.pole_ra_dec_rad,
                        period_s=opts.period_s, phase_rad=opts.phase_rad)
    # a mesh file carries no unit (km is read): a body 1000 times too large is one in metres
    if not 0.1 <= world.size_scale <= 10.0:
        raise InputError(f"{opts.shape}: its volume-equivalent diameter "
                         f"{world.diameter_m / 1e3:.4g} km is not within a factor 10 of the "
                         f"design's {world.diameter_m / world.size_scale / 1e3:.4g} km (a file "
                         "in metres? shape files are read in km)", field="--truth-shape")
    return world


def describe(world: TargetWorld, opts: TruthOptions) -> str:
    """One phrase for the report line: the truth was given, and what it is."""
    from ideas_hpc.body.spin_prior import angles_from_unit

    ra, dec = angles_from_unit(DCM_N_EQ.T @ world.pole_N)
    return (f"truth given ({opts.shape or 'nominal shape'}, {world.shape.n_vertices} vertices, "
            f"D {world.diameter_m / 1e3:.4g} km, pole RA {math.degrees(ra):.2f} Dec "
            f"{math.degrees(dec):.2f} deg, period {world.spin_period_s / HOUR:.4g} h, "
            f"phase {math.degrees(world.phase_tca_rad):.1f} deg at TCA)")
