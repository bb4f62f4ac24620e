"""Seeds only from ``ideas_hpc.base.seeds`` (issue 21 item 6).

The designers' streams moved into ``seeds.py``; they must be the very streams the
old code drew (written out here as the old literal formulas), so designs stay
bit-identical, and no other module may build a generator of its own.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from ideas_hpc.base import seeds

PKG = Path(seeds.__file__).parent


@pytest.mark.parametrize("seed", [0, 1, 7, 2**32 + 5, -3, 123456789012])
def test_search_streams_are_the_old_streams(seed):
    old_ga = np.random.default_rng([seed % 2**32, 13])          # old ga.py:306
    old_pareto = np.random.default_rng([seed % 2**32, 14])      # old design/pareto.py:212
    new_ga = seeds.search_rng(seed, seeds.GA_SEEDING)
    new_pareto = seeds.search_rng(seed, seeds.PARETO_SEARCH)
    assert np.array_equal(old_ga.integers(0, 2**62, 64), new_ga.integers(0, 2**62, 64))
    assert np.array_equal(old_pareto.random(64), new_pareto.random(64))
    assert seeds.search_seed(seed) == seed % 2**32                # old pygad random_seed
    assert not np.array_equal(seeds.search_rng(seed, seeds.GA_SEEDING).random(8),
                              seeds.search_rng(seed, seeds.PARETO_SEARCH).random(8))


def test_plot_stream_is_the_old_jitter():
    assert np.array_equal(seeds.plot_rng().uniform(-0.1, 0.1, 32),
                          np.random.default_rng(0).uniform(-0.1, 0.1, 32))


def _makes_a_stream(node) -> bool:
    if not isinstance(node, ast.Call):
        return False
    f = node.func
    name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", "")
    if name in {"default_rng", "SeedSequence", "RandomState", "seed"}:
        return True
    return any(k.arg == "random_seed" and not (
        isinstance(k.value, ast.Call) and getattr(k.value.func, "id", "") == "search_seed")
        for k in node.keywords)


def test_no_module_outside_seeds_makes_its_own_stream():
    offenders = []
    for path in sorted(PKG.rglob("*.py")):
        if path.name == "seeds.py" and path.parent == PKG:
            continue
        tree = ast.parse(path.read_text())
        offenders += [f"{path.relative_to(PKG)}:{n.lineno}" for n in ast.walk(tree)
                      if _makes_a_stream(n)]
    assert offenders == []


def test_nested_stream_is_its_documented_key_and_apart_from_the_others():
    """``ideas-hpc study``'s nested draws (issue 42): sample ``k`` purpose ``c`` of
    NESTED_STREAM is ``SeedSequence(seed, spawn_key=(NESTED_STREAM, k, c))``, a stream word
    no other family uses."""
    words = {seeds.SCENARIO_STREAM, seeds.VALIDATION_STREAM, seeds.HOLDOUT_STREAM,
             seeds.WORLD_STREAM, seeds.NAVIGATION_STREAM}
    assert seeds.NESTED_STREAM not in words
    got = seeds.stream_rng(7, seeds.NESTED_STREAM, 5, seeds.STREAM_BODY).random(8)
    ref = np.random.default_rng(np.random.SeedSequence(
        7, spawn_key=(seeds.NESTED_STREAM, 5, seeds.STREAM_BODY))).random(8)
    assert np.array_equal(got, ref)
    assert not np.array_equal(got, seeds.stream_rng(7, seeds.VALIDATION_STREAM, 5,
                                                    seeds.STREAM_BODY).random(8))
