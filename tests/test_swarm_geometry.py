"""Swarm spacing (:mod:`ideas_hpc.flyby.swarm_geometry`) against a brute-force oracle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ideas_hpc.base.errors import InputError
from ideas_hpc.campaign.schema.model_fields import flyby_errors
from ideas_hpc.flyby.swarm_geometry import check_separation, closest_pair


def _brute(theta, d_sep):
    """Every pair's 3-D distance between ring points (d cos t, d sin t, 0)."""
    p = np.stack([d_sep * np.cos(theta), d_sep * np.sin(theta)], axis=1)
    best = (math.inf, -1, -1)
    for i in range(len(theta)):
        for j in range(i + 1, len(theta)):
            best = min(best, (float(np.linalg.norm(p[i] - p[j])), i, j))
    return best


@pytest.mark.parametrize("seed", range(20))
def test_closest_pair_matches_brute_force(seed):
    rng = np.random.default_rng(seed)
    theta = rng.uniform(-10.0, 10.0, rng.integers(2, 30))
    d, i, j = _brute(theta, 155.9e3)
    ci, cj, cd = closest_pair(theta, 155.9e3)
    assert cd == pytest.approx(d, rel=1e-9, abs=1e-6)
    # the returned pair is one that realises the minimum (ties allowed): measured here
    assert 0 <= ci < len(theta) and 0 <= cj < len(theta) and ci != cj
    p = 155.9e3 * np.stack([np.cos(theta), np.sin(theta)], axis=1)
    assert float(np.linalg.norm(p[ci] - p[cj])) == pytest.approx(d, rel=1e-9, abs=1e-6)


def test_wrap_around_and_same_track():
    assert closest_pair([0.0, 3.0, 2 * math.pi - 1e-4], 1e5)[:2] == (0, 2)
    assert closest_pair([1.0, 1.0 + 2 * math.pi], 1e5)[2] == pytest.approx(0.0, abs=1e-9)
    assert closest_pair([1.0], 1e5) == (-1, -1, math.inf)


def test_check_separation_names_field_pair_and_distance():
    with pytest.raises(InputError) as ei:
        check_separation([0.2, 1.7, 0.2001], 155.9e3, 1e3)
    e = ei.value   # the flyby layer names its own parameters ...
    assert e.field == "theta" and "spacecraft 0 and 2" in e.message
    assert "0.01559 km apart" in e.message and "`min_separation` = 1" in e.message
    with pytest.raises(InputError) as ei, flyby_errors():   # ... the config layer the file's keys
        check_separation([0.2, 1.7, 0.2001], 155.9e3, 1e3)
    assert ei.value.field == "swarm.angles_rad"
    assert "; the minimum is swarm.min_separation_km = 1" in ei.value.message
    check_separation([0.2, 1.7], 155.9e3, 1e3)  # far apart: accepted
