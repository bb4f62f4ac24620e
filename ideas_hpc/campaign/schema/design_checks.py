"""``[design]`` checks that span keys: the one angle step, and stereo designs.

``design.angle_step_deg`` is the angle grid of every designer: the exact
designer's and design-pareto's candidate swarm angles, and the NP GA's gene
grid (0: continuous GA angles). Each method keeps its own default when the key
is absent (exact and Pareto 0.5 deg, the paper GA 0.01 rad), so designs do not
change. ``design.angle_step_rad``, the GA's former key, is a deprecated alias
that warns once. The typed table keeps the resolved steps under SI names:
``grid_step_rad`` (exact, Pareto) and ``angle_step_rad`` (GA).

The designers raise errors with their own parameter names (field and, between
backticks, in the message); :data:`DESIGNER_FIELDS` maps them to the file's keys
and :func:`designer_errors` applies the map in the campaign layer (issue 21).
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import warnings

from ideas_hpc.design.api.methods import METHODS
from ideas_hpc.design.bank import grid_size
from ideas_hpc.design.stereo import check_grid
from ideas_hpc.campaign.schema.kinds import KINDS
from ideas_hpc.campaign.schema.model_fields import FLYBY_FIELDS
from ideas_hpc.base.errors import InputError, config_fields
from ideas_hpc.base.units import DEG

STEP_KEY = "design.angle_step_deg"
ALIAS_KEY = "design.angle_step_rad"
#: The designers' parameter names (``ideas_hpc.design``) -> the campaign file's keys.
DESIGNER_FIELDS = {
    "n_max": "design.n_max", "time_limit": "design.time_limit_s", "eps_tol": "design.eps_tol_pct",
    "k": "design.failures_tolerated", "p": "design.success_probability",
    "confidence": "design.confidence", "objectives": "design.objectives", "step": STEP_KEY,
    "min_separation": "swarm.min_separation_km", "require_stereo": "coverage.require_stereo",
    "rule": "design.target_rule",
}
EXACT_STEP_RAD = 0.5 * DEG   #: exact designer and design-pareto default grid, rad
GA_STEP_RAD = 0.01           #: the paper GA's default gene grid, rad
_warned: list = []


def _warn_alias() -> None:
    if not _warned:
        _warned.append(True)
        warnings.warn(f"{ALIAS_KEY} is deprecated: use {STEP_KEY} (one grid for every "
                      "designer)", FutureWarning, stacklevel=3)


@contextlib.contextmanager
def designer_errors(c=None):
    """Re-raise a designer's (or the flyby layer's) :class:`InputError` under the file's key
    (:data:`DESIGNER_FIELDS`, :data:`~ideas_hpc.campaign.schema.model_fields.FLYBY_FIELDS`), with
    its file and line when the campaign ``c`` is given."""
    try:
        with config_fields({**FLYBY_FIELDS, **DESIGNER_FIELDS}):   # designs fly setups too
            yield
    except InputError as exc:
        if c is None or exc.file is not None or not exc.field:
            raise
        raise c.error(exc.message, exc.field) from None


def step_key(raw_design) -> str:
    """The key that set the angle step (``raw_design``: the file's ``[design]`` table):
    the alias when the file used it alone."""
    raw = raw_design if isinstance(raw_design, dict) else {}
    return ALIAS_KEY if "angle_step_rad" in raw and "angle_step_deg" not in raw else STEP_KEY


def resolve_angle_step(config):
    """``config`` with ``design.grid_step_rad`` and ``design.angle_step_rad`` resolved."""
    d = config.design
    deg, alias = d.grid_step_rad, d.angle_step_rad
    if alias is not None:
        _warn_alias()
        if deg is not None and not math.isclose(deg, alias, rel_tol=1e-12):
            raise InputError(f"is a deprecated alias of {STEP_KEY}, which gives another step; "
                             f"keep {STEP_KEY} only", field=ALIAS_KEY)
    step = deg if deg is not None else alias
    ga = d.method in KINDS[config.kind].continuous_methods
    if step is not None and step <= 0 and not ga:
        raise InputError("must be > 0 (0, continuous angles, is for the GA only)",
                         field=ALIAS_KEY if deg is None else STEP_KEY)
    design = dataclasses.replace(
        d, grid_step_rad=EXACT_STEP_RAD if step is None or step <= 0 else step,
        angle_step_rad=GA_STEP_RAD if step is None else step)
    return dataclasses.replace(config, design=design)


def check_stereo_design(config, raw_design) -> None:
    """A design campaign with ``coverage.require_stereo``: the NP designers score pairs
    (``raw_design``: the file's ``[design]`` table, to name the key it used)."""
    d = config.design
    if not KINDS[config.kind].stereo:
        able = " or ".join(k.name for k in KINDS.values() if k.stereo)
        raise InputError(f"stereo from two spacecraft is a condition on pairs, which kind "
                         f"{config.kind!r} cannot score; use kind {able}",
                         field="coverage.require_stereo")
    key = step_key(raw_design)
    if METHODS[d.method].continuous_angles:
        if not d.angle_step_rad > 0:
            raise InputError(f"the GA scores stereo pairs on its angle grid: set {key} > 0",
                             field=key)
        check_grid(grid_size(d.angle_step_rad, key), key)
    check_grid(grid_size(d.grid_step_rad, key), key)
    if d.failures_tolerated:
        raise InputError("failure tolerance with stereo from two spacecraft is not solved yet; "
                         "set design.failures_tolerated = 0 (the Monte Carlo verification "
                         "still flies failures)", field="design.failures_tolerated")
