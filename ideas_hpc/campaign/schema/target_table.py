"""The ``[target]`` table: what is known of the target before the flyby (SPEC 7f, issue 42).

``prior``: ``"known"`` (default: the campaign's ``[body]``, exactly; every scenario flies
it, rows bit-identical to a campaign without the table) or ``"eros-class"`` (the
built-in prior of an Eros-class target, :func:`ideas_hpc.body.target_prior.eros_class_prior`:
Gaussian random spheres on the Eros-sized ellipsoid, its size, pole and rotation
spreads). ``"eros-class"`` supplies the body: its nominal ellipsoid meshed at
``body.resolution``, with Eros' Table 1 orbit, mass and spin, and the prior's pole
and rotation phase (:func:`ideas_hpc.campaign.target.prior_body`); no data file is
read, and ``body.name``, ``body.params``, ``body.data_path``, ``body.shape`` and
``body.kernels`` are refused as not read. Scenario ``s`` of the bank then flies world
``s`` of the prior (:mod:`ideas_hpc.flyby.target_world`).

Overrides of the prior's spreads (``"eros-class"`` only; default: the prior's own):

``sigma_r``
    relative 1-sigma of the radius of the Gaussian random sphere (0.245; 0: the
    nominal shape);
``correlation_deg``
    correlation angle of the log-radius, deg (33);
``sigma_diameter_pct``
    1-sigma of the volume-equivalent diameter, % of the nominal (10);
``sigma_pole_deg``
    1-sigma of the pole per axis, deg (10);
``p_mirror``
    probability that the mirror pole is the true one (0.25);
``sigma_phase_deg``
    1-sigma of the rotation phase at the last lightcurve epoch, deg (10);
``lightcurve_days``
    days from the last lightcurve epoch to closest approach (60): with the period's
    1-sigma it sets the phase's spread at closest approach, uniform beyond 180 deg
    (:mod:`ideas_hpc.body.spin_prior`, the rule).
"""

from __future__ import annotations

from ideas_hpc.base.fields import Field
from ideas_hpc.campaign.schema.read_settings import Rule
from ideas_hpc.base.units import DEG

DAY_S = 86400.0
PRIORS = ("known", "eros-class")

TARGET = {
    "prior": Field("str", "known", choices=PRIORS,
                   doc="known: the [body], exactly; eros-class: the built-in prior"),
    "sigma_r": Field("float", None, nullable=True, lo=0.0, hi=2.0,
                     doc="relative 1-sigma of the radius (Gaussian random sphere)"),
    "correlation_deg": Field("float", None, nullable=True, si="correlation_rad", to_si=DEG,
                             lo=0.0, lo_open=True, hi=180.0,
                             doc="correlation angle of the log-radius"),
    "sigma_diameter_pct": Field("float", None, nullable=True, si="sigma_diameter", per=100.0,
                                lo=0.0, hi=100.0, doc="1-sigma of the diameter, % of nominal"),
    "sigma_pole_deg": Field("float", None, nullable=True, si="sigma_pole_rad", to_si=DEG,
                            lo=0.0, hi=180.0, doc="1-sigma of the spin pole per axis"),
    "p_mirror": Field("float", None, nullable=True, lo=0.0, hi=1.0,
                      doc="probability that the mirror pole is the true one"),
    "sigma_phase_deg": Field("float", None, nullable=True, si="sigma_phase_rad", to_si=DEG,
                             lo=0.0, doc="1-sigma of the rotation phase at the last lightcurve"),
    "lightcurve_days": Field("float", None, nullable=True, si="lightcurve_s", to_si=DAY_S,
                             lo=0.0, doc="days from the last lightcurve to closest approach"),
}

#: The spread overrides (every key but ``prior``): read with a drawn prior only
#: (:mod:`ideas_hpc.campaign.schema.reads`).
SPREADS = tuple(k for k in TARGET if k != "prior")


def drawn(s) -> bool:
    """A drawn target prior (``target.prior`` not "known") supplies the body (settings
    ``s`` of :mod:`ideas_hpc.campaign.schema.read_settings`)."""
    return s.config.target.prior != "known"


def why_drawn(s) -> str:
    return (f"is ignored with target.prior = {s.config.target.prior!r}: the prior supplies "
            "the body (its nominal, meshed at body.resolution)")


#: The key-read rules of the prior (:data:`ideas_hpc.campaign.schema.reads.RULES`): a
#: drawn prior's body keys are not read, nor are the spreads of the known prior.
TARGET_RULES = {
    **{f"body.{k}": Rule(lambda s: not drawn(s), why_drawn)
       for k in ("name", "params", "data_path", "shape", "kernels")},
    **{f"target.{k}": Rule(drawn, lambda s: 'overrides a drawn prior\'s spread: set '
                                             'target.prior = "eros-class"') for k in SPREADS},
}
