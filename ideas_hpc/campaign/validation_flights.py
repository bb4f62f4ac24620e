"""Validation and held-out flights of a success-probability design, with their vertex weights.

The chosen swarm is flown through fresh samples (:class:`Validation`: per sample the exact
failure-weighted P and one drawn outcome, :mod:`ideas_hpc.failures.sampling`). On a known
body every sample shares the bank's vertex weights. When each sample is a drawn world
(issue 42: a drawn shape on the same mesh, a reference area such as the surface lit at
closest approach), vertex v weighs differently in each sample, and those weights come
with the flights.

Expected interface of the flight functions (:mod:`ideas_hpc.montecarlo.scenarios`), read
tolerantly by :func:`unpack_flights`:

* today: ``fly_members`` returns ``rows`` (M, N, V) bool and ``fly_members_seen``
  ``(rows, seen)`` with ``seen`` (M, N, V) float: the bank's weights apply;
* drawn worlds: either an object with attributes ``rows``, ``areas`` (M, V) (and ``seen``
  for the timed flights), or a tuple whose first item is ``rows`` and whose other items
  are ``seen`` (3-D) and ``areas`` (M, V) or (V,) (2-D or 1-D), in any order. ``areas``
  are vertex areas (m^2, zero outside the sample's reference area) or fractions: each
  sample's row is normalised here (:func:`ideas_hpc.base.vertex_weights.normalised`).

A bank whose weights differ by scenario with flights that bring none is an input error
(field ``areas``): the bank's scenarios say nothing about a fresh sample's world.
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.base import seeds
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.vertex_weights import normalised, per_scenario
from ideas_hpc.failures.model import as_model
from ideas_hpc.failures.sampling import drawn_coverage, sample_probabilities, validation_failures
from ideas_hpc.montecarlo.scenarios import flight_areas, fly_members, fly_members_seen


def unpack_flights(out) -> tuple:
    """``(rows, seen or None, areas or None)`` from what a flight function returned (module
    docstring)."""
    if hasattr(out, "rows"):
        return out.rows, getattr(out, "seen", None), getattr(out, "areas", None)
    if not isinstance(out, tuple):
        return out, None, None
    rows, seen, areas = out[0], None, None
    for item in out[1:]:
        if item is None:
            continue
        a = np.asarray(item)
        if a.ndim == 3:
            seen = item
        else:
            areas = item
    return rows, seen, areas


def sample_weights(areas, bank_w: np.ndarray, m: int) -> np.ndarray:
    """The vertex fractions of M flown samples: theirs when the flights gave them (each
    normalised), else the bank's shared weights (module docstring)."""
    if areas is not None:
        return normalised(areas, m, field="areas")
    if per_scenario(bank_w):
        raise InputError("the bank's vertex weights differ by scenario (drawn worlds) but the "
                         "validation flights gave no per-sample weights", field="areas")
    return bank_w


class Validation:
    """The chosen swarm flown through fresh samples (module docstring): per sample the
    exact failure-weighted P and one drawn outcome (``seen``: the first-seen times of
    losses in the pass, None: whole-pass). ``w``: vertex fractions, (V,) shared or (M, V)
    per sample (:func:`sample_weights`)."""

    def __init__(self, rows, w, need, model, seed: int, first: int = 0, seen=None,
                 stream: int = seeds.VALIDATION_STREAM):
        model = as_model(model)
        self.first = int(first)
        draws = validation_failures(model, rows.shape[1], seed, self.first, rows.shape[0],
                                    stream)
        self.per_sample = sample_probabilities(rows, w, need, model, draws, seen)
        self.p_hat = float(self.per_sample.mean())
        # the bound at the look's share of the error is computed once, by certify(): its
        # look's value is copied here (_certify); None for flights that are no look
        self.lower = None
        self.coverage, self.n_failed = drawn_coverage(rows, w, draws, seen)


def fly_validation_world(setup, theta, mc, model, requirement=None, **keywords) -> tuple:
    """``(rows, seen, areas)`` of validation flights (:func:`unpack_flights`): with losses in
    the pass and seen rows, when each member first sees each vertex
    (:func:`~ideas_hpc.montecarlo.scenarios.fly_members_seen`); else ``seen = None``
    (whole-pass losses). ``areas`` None: the flights share the bank's weights; with a
    target prior, each sample's world's reference area of ``requirement`` (its vertex
    areas when None; :func:`~ideas_hpc.montecarlo.scenarios.flight_areas`)."""
    if model.in_pass_share > 0.0 and not setup.coverage.requirement:
        rows, seen, areas = unpack_flights(fly_members_seen(setup, theta, mc, **keywords))
    else:
        rows, _, areas = unpack_flights(fly_members(setup, theta, None, mc, **keywords))
        seen = None
    if areas is None and setup.target is not None:
        areas = flight_areas(setup, seed=keywords["seed"], n_samples=rows.shape[0],
                             first=keywords.get("first", 0),
                             stream=keywords.get("stream", seeds.VALIDATION_STREAM),
                             requirement=requirement)
    return rows, seen, areas


def fly_validation(setup, theta, mc, model, **keywords):
    """``(rows, seen)`` of :func:`fly_validation_world` (its weights dropped: the store
    validation's interface)."""
    rows, seen, _ = fly_validation_world(setup, theta, mc, model, **keywords)
    return rows, seen
