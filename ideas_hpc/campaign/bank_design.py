"""The scenario bank of a campaign and the fewest-N search on it: the two steps of the
success-probability design (:mod:`ideas_hpc.campaign.design_reliability`) that
``ideas-hpc study`` (:mod:`ideas_hpc.campaign.study`) repeats on variants of the same
campaign (the known target, other navigation updates)."""

from __future__ import annotations

import dataclasses
import math

from ideas_hpc.base import progress, seeds
from ideas_hpc.base.errors import InputError
from ideas_hpc.campaign.schema.design_checks import designer_errors
from ideas_hpc.campaign.setup import requirement_from_campaign
from ideas_hpc.design.api import ScenarioProblem, minimize
from ideas_hpc.design.bank import grid_size, separation_steps
from ideas_hpc.design.settings import ReliableSettings
from ideas_hpc.flyby.target_world import world_areas
from ideas_hpc.montecarlo.failure_dispersion import failure_model
from ideas_hpc.montecarlo.scenarios import build_scenario_bank


def campaign_bank(c, setup, n_scenarios: int, client=None, store: str | None = None):
    """The campaign's scenario bank of ``setup`` (``n_scenarios`` draws of the
    ``[monte_carlo]`` and navigation dispersions and, with a target prior, one world each;
    :func:`~ideas_hpc.montecarlo.scenarios.build_scenario_bank`), with each world's
    reference area as its weights under a ``design.coverage_reference``. ``store``: the
    bank's own zarr store (reused while its shaping config is unchanged)."""
    bank = build_scenario_bank(setup, c.config.design.grid_step_rad, c.config.monte_carlo,
                               seed=c.config.seed, n_scenarios=int(n_scenarios),
                               client=client, store=store, progress=progress.on())
    if c.config.design.coverage_reference != "surface":   # each world's reference area
        bank = dataclasses.replace(bank, areas=world_areas(
            setup, c.config.seed, seeds.SCENARIO_STREAM, range(int(n_scenarios)),
            requirement_from_campaign(c)))
    return bank


def bank_settings(c, setup, threshold, level: float, time_limit_s: float) -> ReliableSettings:
    """The fewest-N search on a campaign's bank at ``level`` (``threshold``: the requirement's
    :class:`~ideas_hpc.mapping.requirement.Threshold` or its ``need``), with the
    campaign's failure model, ``n_max`` and separation."""
    d = c.config.design
    model = failure_model(c.config.monte_carlo)
    n_grid = grid_size(d.grid_step_rad)
    m_sep = separation_steps(2 * math.pi / n_grid, setup.d_sep_m,
                             c.config.swarm.min_separation_m, n_grid)
    thr = threshold if hasattr(threshold, "need") else None
    return ReliableSettings(p=float(level), p_f=model.p_f[0],
                            need=None if thr is not None else float(threshold),
                            threshold=thr, n_max=d.n_max, sep_steps=m_sep,
                            time_limit_s=time_limit_s, failures=model)


def bank_search(c, setup, bank, threshold, level: float, time_limit_s: float):
    """The proven fewest N on ``bank`` at ``level`` (:func:`bank_settings`): the search's
    detail (:class:`~ideas_hpc.design.reliability.ReliableResult`). A level no swarm of
    ``n_max`` reaches is one :class:`InputError` naming ``design.success_probability``, or
    ``design.bank_level`` when the bank is solved at that stricter level."""
    p = float(c.config.design.success_probability)
    try:
        with designer_errors(c):
            return minimize(ScenarioProblem(bank.rows, bank.areas, bank.theta),
                            bank_settings(c, setup, threshold, level, time_limit_s)).detail
    except InputError as exc:
        if level == p or exc.field != "design.success_probability":
            raise
        raise c.error(f"{exc.message} (the stricter level the bank is solved at)",
                      "design.bank_level") from None


def bank_level(d) -> float:
    """p': the level the bank is solved at (``design.bank_level``, else p)."""
    return float(d.success_probability) if d.bank_level is None else float(d.bank_level)


def search_budget(d, spent_s: float) -> float:
    """What ``design.time_limit_s`` leaves the bank's search after ``spent_s`` of the
    nominal design's searches (issue 29: one limit bounds the phase's searches)."""
    return max(1e-3, float(d.time_limit_s) - max(0.0, spent_s))


def refuse_stereo(c, setup) -> None:
    """Stereo pairs are not in the scenario bank: refused, naming the design's key."""
    if setup.coverage.require_stereo:
        raise c.error("is not supported with coverage.require_stereo (stereo pairs are not in "
                      "the scenario bank)", "design.success_probability")
