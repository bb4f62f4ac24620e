"""Per-scenario vertex weights (issue 42): every scenario (and every validation or held-out
sample) may be a different world, with its own vertex areas and reference area on the same
mesh. Oracles: plain NumPy sums over survivor subsets and exhaustive search over swarms,
and a copy of the kernel as it was before (shared weights must give the same floats)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.vertex_weights import normalised
from ideas_hpc.campaign.reliability_vars import world_vars
from ideas_hpc.campaign.validation_flights import sample_weights, unpack_flights
from ideas_hpc.core.design.reliability import (independent_weights, swarm_coverages,
                                               weighted_probabilities)
from ideas_hpc.design.holdout import HeldOut
from ideas_hpc.design.reliability import ReliabilityDesigner, min_swarm_reliable
from ideas_hpc.design.reliability_eval import Evaluator
from ideas_hpc.design.scenario_mip import ScenarioMIP
from ideas_hpc.failures.model import as_model
from ideas_hpc.failures.sampling import FailureDraw, drawn_coverage, sample_probabilities
from test_failure_model import _old_kernel   # the kernel before issues 41 and 42, copied

P_F, NEED, P = 0.1, 0.85, 0.7


def brute_ps(rows, w2, members, need, p_f, sure=None):
    """(S,) sum over survivor subsets T of q^|T| p_f^(N-|T|) [sum of w2[s] over what T (or
    ``sure[s]``) sees >= need], plain NumPy."""
    s_n, n = rows.shape[0], len(members)
    out = np.zeros(s_n)
    for s in range(s_n):
        for t in range(1 << n):
            alive = [members[i] for i in range(n) if t >> i & 1]
            seen = rows[s, alive].any(axis=0) if alive else np.zeros(rows.shape[2], bool)
            if sure is not None:
                seen = seen | sure[s]
            if w2[s][seen].sum() >= need - 1e-12:
                out[s] += (1 - p_f) ** len(alive) * p_f ** (n - len(alive))
    return out


def best_true(rows, w2, n):
    """Largest bank P of any n-swarm (exhaustive, brute force)."""
    return max(brute_ps(rows, w2, c, NEED, P_F).mean()
               for c in itertools.combinations(range(rows.shape[1]), n))


def fewest_true(rows, w2, n_max):
    for n in range(1, n_max + 1):
        if best_true(rows, w2, n) >= P - 1e-12:
            return n
    return None


def world_bank(seed, s_n=4, c_n=8, v_n=14):
    """Random rows and per-scenario areas, a fifth of each world's vertices outside its
    reference (weight 0)."""
    rng = np.random.default_rng(seed)
    rows = rng.random((s_n, c_n, v_n)) < 0.35
    areas = rng.random((s_n, v_n)) * (rng.random((s_n, v_n)) < 0.8)
    return rows, areas


def test_kernel_and_evaluator_match_brute_force_per_scenario():
    rows, areas = world_bank(11, s_n=5, c_n=7, v_n=20)
    w2 = normalised(areas)
    np.testing.assert_allclose(w2.sum(axis=1), 1.0, rtol=0, atol=1e-15)
    ev = Evaluator(rows, w2, NEED, P_F)
    for sw in ([0, 3, 5], [1, 2, 4, 6], [0, 1, 2, 3, 4]):
        want = brute_ps(rows, w2, sw, NEED, P_F)
        got = weighted_probabilities(np.ascontiguousarray(rows), np.array([sw], np.int64), w2,
                                     NEED, independent_weights(P_F, len(sw)))[0]
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
        np.testing.assert_allclose(ev.per_scenario([sw])[0], want, rtol=0, atol=1e-12)
        cov = [w2[s][rows[s, sw].any(axis=0)].sum() for s in range(5)]
        np.testing.assert_allclose(swarm_coverages(ev.rows, np.array([sw]), w2)[0], cov,
                                   rtol=0, atol=1e-14)
        # scenario 0's weights for every scenario are another bank: the test sees the rows
        assert not np.allclose(Evaluator(rows, w2[0], NEED, P_F).per_scenario([sw])[0], want,
                               atol=1e-9) or len(sw) == 5
    reach = [w2[s][rows[s].any(axis=0)].sum() for s in range(5)]
    np.testing.assert_allclose(ev.reach(), reach, rtol=0, atol=1e-14)
    np.testing.assert_allclose(world_vars(rows, areas)["scenario_reach"].values, reach,
                               rtol=0, atol=1e-14)


def test_shared_weights_give_the_floats_of_before():
    """(V,), (1, V) and (S, V) of identical rows: the same floats as the kernel before issue 42."""
    rng = np.random.default_rng(5)
    rows = np.ascontiguousarray(rng.random((6, 9, 40)) < 0.3)
    a = rng.uniform(0.2, 3.0, 40)
    w = a / a.sum()                                   # the designer's normalisation before
    tiled = normalised(np.tile(a, (6, 1)))
    assert np.array_equal(normalised(a), w) and np.array_equal(tiled[3], w)
    swarms = np.array([[0, 2, 4, 6], [1, 3, 5, 8], [0, 1, 7, 8]], np.int64)
    weights = independent_weights(P_F, 4)
    old = np.array([[_old_kernel(rows, s, sw, w, 0.6, P_F) for s in range(6)]
                    for sw in swarms])
    for ww in (w, w[None, :].copy(), tiled):
        assert np.array_equal(weighted_probabilities(rows, swarms, ww, 0.6, weights), old)
        ev = Evaluator(rows, ww, 0.6, P_F)
        assert np.array_equal(ev.per_scenario(swarms), old)
        assert np.array_equal(ev.scored(swarms), Evaluator(rows, w, 0.6, P_F).scored(swarms))
    m_rows = rows[:, swarms[0]]          # validation rows: (M, N, V) of one swarm
    for ww in (w, tiled):
        assert np.array_equal(sample_probabilities(m_rows, ww, 0.6, as_model(P_F), None),
                              old[0])
    r1 = min_swarm_reliable(rows, a, p=0.8, p_f=P_F, need=0.6, n_max=6)
    r2 = min_swarm_reliable(rows, np.tile(a, (6, 1)), p=0.8, p_f=P_F, need=0.6, n_max=6)
    assert r1.n == r2.n and r1.probability == r2.probability
    assert np.array_equal(r1.per_scenario, r2.per_scenario) and r1.upper == r2.upper


#: Banks whose fewest N differs when scenario 0's weights are used for every scenario.
DIFFERS = (0, 3, 10)


@pytest.mark.parametrize("seed", [0, 1, 3, 5, 10])
def test_designer_fewest_n_is_the_exhaustive_one(seed):
    rows, areas = world_bank(seed)
    w2 = normalised(areas)
    n_true = fewest_true(rows, w2, 6)
    if seed in DIFFERS:     # the subject: weights by scenario change the answer
        assert fewest_true(rows, np.repeat(w2[:1], 4, axis=0), 6) != n_true
    assert n_true is not None
    r = min_swarm_reliable(rows, areas, p=P, p_f=P_F, need=NEED, n_max=6)
    assert r.n == n_true and r.probability >= P - 1e-12
    np.testing.assert_allclose(r.per_scenario, brute_ps(rows, w2, r.indices, NEED, P_F),
                               atol=1e-12)


@pytest.mark.parametrize("seed", DIFFERS)
def test_every_proof_holds_with_weights_by_scenario(seed):
    """Without enumeration the designer rests on its bounds: every proven UB(n) is at least
    the exhaustive best P of n, every ring-gap low at most the scenario's own fewest
    covering N, the scenario programme's Ubar_m at least the true U_m; N is never below
    the exhaustive one, and equal when proven optimal."""
    rows, areas = world_bank(seed)
    w2 = normalised(areas)
    n_true = fewest_true(rows, w2, 6)
    try:
        r = min_swarm_reliable(rows, areas, p=P, p_f=P_F, need=NEED, n_max=6,
                               enumerate_budget=0)
        assert r.n >= n_true and (r.status != "optimal" or r.n == n_true)
        for n, ub in r.upper.items():
            assert ub >= best_true(rows, w2, n) - 1e-12, (n, ub)
    except InputError:      # nothing found within n_max: no proof claimed N short
        pass
    d = ReliabilityDesigner(rows, areas, need=NEED, p_f=P_F)
    lows = d.ring_lows(6)
    mip = ScenarioMIP(d.ev.rows, d.ev.w, NEED, 0)
    for m in range(1, 6):
        covers = np.zeros(4, bool)
        best_u = 0
        for c in itertools.combinations(range(8), m):
            ok = np.array([w2[s][rows[s, list(c)].any(axis=0)].sum() >= NEED - 1e-12
                           for s in range(4)])
            covers |= ok
            best_u = max(best_u, int(ok.sum()))
        assert np.all(lows[covers] <= m), (m, lows, covers)
        assert mip.solve(m, None).upper >= best_u
    tol = d.tolerance()
    for n in range(1, 7):
        assert tol.upper(n, d.model, None) >= best_true(rows, w2, n) - 1e-12
    for s in range(4):      # each k-tolerant minimum bound is its own world's
        for k, low in tol.lows[s].items():
            assert low <= fewest_tolerant(rows[s], w2[s], k), (s, k, low)


def fewest_tolerant(rows_s, w, k):
    """Fewest candidates of which every subset left after any k failures covers NEED in one
    scenario (exhaustive; 9 when none of 8 does)."""
    c_n = rows_s.shape[0]
    for n in range(k + 1, c_n + 1):
        for c in itertools.combinations(range(c_n), n):
            if all(w[rows_s[list(t)].any(axis=0)].sum() >= NEED - 1e-12
                   for t in itertools.combinations(c, n - k)):
                return n
    return c_n + 1


def test_held_out_rows_with_weights_by_scenario():
    rows, areas = world_bank(21, s_n=6, c_n=7, v_n=25)
    w2 = normalised(areas)
    held = HeldOut.of_rows(rows, w2, NEED, P_F)
    for sw in ([0, 2, 5], [1, 3, 4, 6]):
        np.testing.assert_allclose(held.values(sw), brute_ps(rows, w2, sw, NEED, P_F),
                                   rtol=0, atol=1e-12)


def test_validation_with_per_sample_weights_and_losses_in_the_pass():
    """Per-sample weights, with and without members lost in the pass (a vertex a lost member
    imaged before its loss counts whatever fails): exact P and drawn coverage by brute force."""
    rng = np.random.default_rng(8)
    m_n, n, v_n = 5, 4, 18
    rows = rng.random((m_n, n, v_n)) < 0.4
    w2 = normalised(rng.random((m_n, v_n)) * (rng.random((m_n, v_n)) < 0.8))
    members = list(range(n))
    model = as_model(P_F)
    np.testing.assert_allclose(sample_probabilities(rows, w2, 0.8, model, None),
                               brute_ps(rows, w2, members, 0.8, P_F), rtol=0, atol=1e-12)
    seen = np.where(rows, rng.random((m_n, n, v_n)), np.inf).astype(np.float32)
    draws = [FailureDraw(failed=rng.random(n) < 0.4, in_pass=rng.random(n) < 0.6,
                         loss_fraction=rng.random(n)) for _ in range(m_n)]
    sure = np.array([(d.in_pass[:, None] & (seen[k] < d.loss_fraction[:, None])).any(axis=0)
                     for k, d in enumerate(draws)])
    assert sure.any()
    np.testing.assert_allclose(sample_probabilities(rows, w2, 0.8, model, draws, seen),
                               brute_ps(rows, w2, members, 0.8, P_F, sure), rtol=0, atol=1e-12)
    cov, lost = drawn_coverage(rows, w2, draws, seen)
    for k, d in enumerate(draws):
        got = rows[k, ~d.failed].any(axis=0) | (
            d.failed[:, None] & d.in_pass[:, None] & (seen[k] < d.loss_fraction[:, None])
        ).any(axis=0)
        assert cov[k] == pytest.approx(w2[k][got].sum(), abs=1e-14)
        assert lost[k] == d.failed.sum()


def test_flight_interface_and_input_errors():
    rows = np.zeros((3, 2, 5), bool)
    areas = np.arange(15.0).reshape(3, 5) + 1.0
    seen = np.zeros((3, 2, 5), np.float32)
    assert unpack_flights(rows)[1:] == (None, None)
    r, s, a = unpack_flights((rows, seen, areas))
    assert r is rows and s is seen and a is areas
    r, s, a = unpack_flights((rows, areas))
    assert s is None and a is areas

    class Flown:
        pass
    f = Flown()
    f.rows, f.areas = rows, areas
    assert unpack_flights(f)[2] is areas
    w = sample_weights(areas, np.full(5, 0.2), 3)
    np.testing.assert_allclose(w.sum(axis=1), 1.0)
    shared = np.full(5, 0.2)
    assert sample_weights(None, shared, 3) is shared
    with pytest.raises(InputError) as exc:
        sample_weights(None, normalised(areas), 3)
    assert exc.value.field == "areas"
    bad = areas.copy()
    bad[1] = 0.0
    for a in (bad, np.zeros(5), areas[:2]):
        with pytest.raises(InputError) as exc:
            normalised(a, 3)
        assert exc.value.field == "areas"
    with pytest.raises(InputError):
        Evaluator(np.zeros((3, 2, 5), bool), np.ones((2, 5)) / 5, 0.5, P_F)
