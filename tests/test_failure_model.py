"""The failure model (issue 41): today's numbers bit for bit, exact P against brute force and
against a direct Monte Carlo of the same model, the proofs' upper law really above P, and
``failures_k`` honoured."""

from __future__ import annotations

import itertools
import math
from types import SimpleNamespace

import numpy as np
import pytest
from numba import njit
from scipy import integrate, stats
from scipy.special import beta as beta_fn

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.seeds import sample_rng
from ideas_hpc.core.design.reliability import independent_weights, weighted_probabilities
from ideas_hpc.design.reliability import min_swarm_reliable
from ideas_hpc.design.reliability_eval import Evaluator
from ideas_hpc.design.reliability_search import all_swarms
from ideas_hpc.failures import FailureModel, Prior
from ideas_hpc.failures.sampling import draw_failures, sample_probabilities, FailureDraw
from ideas_hpc.failures.sums import count_envelope, downset_bound, level_bound, screen_terms
from ideas_hpc.failures.weights import all_lost, survivor_weights
from ideas_hpc.montecarlo import failure_dispersion


@njit(cache=True)
def _old_kernel(rows, s, members, w, need, p_f):
    """The exact kernel as it was before issue 41 (its float operations written out)."""
    n = members.size
    full = (1 << n) - 1
    f = np.zeros(1 << n)
    total = 0.0
    for v in range(w.size):
        b = 0
        for i in range(n):
            if rows[s, members[i], v]:
                b |= 1 << i
        f[b] += w[v]
        total += w[v]
    for i in range(n):
        bit = 1 << i
        for m in range(1 << n):
            if m & bit:
                f[m] += f[m ^ bit]
    q = 1.0 - p_f
    out = 0.0
    for t in range(1 << n):
        if total - f[full ^ t] >= need - 1e-12:
            k = 0
            x = t
            while x:
                x &= x - 1
                k += 1
            out += q ** k * p_f ** (n - k)
    return out


def random_rows(seed, s_n=4, c_n=8, v_n=30, density=0.35):
    rng = np.random.default_rng(seed)
    rows = rng.random((s_n, c_n, v_n)) < density
    w = rng.uniform(0.5, 1.5, v_n)
    return rows, w / w.sum()


def covered_table(rows, swarm, w, need):
    """(S, 2^n) bool: survivors ``mask`` of ``swarm`` cover ``need`` in scenario s (numpy)."""
    n = len(swarm)
    out = np.zeros((rows.shape[0], 1 << n), dtype=bool)
    for s in range(rows.shape[0]):
        for mask in range(1 << n):
            mem = [swarm[i] for i in range(n) if mask >> i & 1]
            out[s, mask] = bool(mem) and w[rows[s, mem].any(axis=0)].sum() >= need - 1e-12
    return out


def exact(model, rows, swarm, w, need):
    sw = np.asarray([swarm], dtype=np.int64)
    return float(weighted_probabilities(rows, sw, w, need,
                                        survivor_weights(model, len(swarm)).score).mean())


# ----------------------------------------------------------------- today's numbers, bit for bit
@pytest.mark.parametrize("seed", range(6))
def test_kernel_with_weights_is_the_old_kernel_bit_for_bit(seed):
    rng = np.random.default_rng(100 + seed)
    rows, w = random_rows(seed, c_n=10)
    for _ in range(20):
        n = int(rng.integers(1, 8))
        sw = np.sort(rng.choice(10, n, replace=False)).astype(np.int64)
        p_f = float(rng.choice([0.05, 0.1, 0.013, rng.random() * 0.5]))
        need = float(rng.uniform(0.2, 0.9))
        weights = survivor_weights(FailureModel.fixed(p_f), n).score
        got = weighted_probabilities(rows, sw[None], w, need, weights)[0]
        old = np.array([_old_kernel(rows, s, sw, w, need, p_f) for s in range(rows.shape[0])])
        assert np.array_equal(got, old)          # the same floats, not merely close


@pytest.mark.parametrize("p_f", [0.05, 0.1, 0.0137, 0.31])
def test_bound_sums_are_the_old_sums_bit_for_bit(p_f):
    rng = np.random.default_rng(7)
    q = 1.0 - p_f
    for n in range(2, 14):
        u = [0.0] + list(rng.random(n))
        old_level = min(1.0, sum(math.comb(n, j) * p_f ** j * (1.0 - p_f) ** (n - j) * u[n - j]
                                 for j in range(n + 1)))
        assert level_bound(n, np.asarray(u), p_f) == old_level
        base, one = screen_terms(n, u, p_f)
        rest = sum(math.comb(n, j) * p_f ** j * q ** (n - j) * u[n - j] for j in range(2, n + 1))
        assert base == q ** n * u[n] + rest and one == p_f * q ** (n - 1)
        for n0, ks in ((1, None), (2, 1), (n // 2, 2)):
            out = 0.0
            for j in range(0, n - max(n0, 0) + 1):
                cnt = math.comb(n, j)
                if ks is not None and 1 <= ks <= j:
                    cnt -= math.comb(n - ks, j - ks)
                out += p_f ** j * (1.0 - p_f) ** (n - j) * cnt
            assert downset_bound(n, p_f, n0, ks) == min(1.0, out)
        assert all_lost(FailureModel.fixed(p_f), n) == p_f ** n


# ----------------------------------------------------------------- exact weights against oracles
def test_beta_prior_weights_are_the_beta_function_ratio():
    """E[(1 - p)^k p^(N - k)] for p ~ Beta(a, b) is B(a + N - k, b + k) / B(a, b)."""
    for mean, sd in ((0.05, 0.02), (0.2, 0.1), (0.5, 0.25)):
        m = FailureModel(p_f=(mean,), prior=Prior(mean=mean, sd=sd))
        a, b = m.prior.ab
        assert a / (a + b) == pytest.approx(mean, rel=1e-12)
        assert math.sqrt(a * b / ((a + b) ** 2 * (a + b + 1))) == pytest.approx(sd, rel=1e-12)
        for n in (1, 4, 9, 16):
            want = np.array([beta_fn(a + n - k, b + k) / beta_fn(a, b) for k in range(n + 1)])
            np.testing.assert_allclose(survivor_weights(m, n).score, want, rtol=1e-11, atol=0)


def brute_mask_law(q, beta, groups, n):
    """pi(T) by explicit products over every independent pattern and every group event."""
    law = np.zeros(1 << n)
    for indep in range(1 << n):                     # bit set: independent failure
        pi = 1.0
        for j in range(n):
            r = (1 - beta) * q[j]
            pi *= r if indep >> j & 1 else 1 - r
        for events in range(1 << len(groups)):
            pe = 1.0
            dead = indep
            for g_i, g in enumerate(groups):
                c = beta * max(q[j] for j in g)
                if events >> g_i & 1:
                    pe *= c
                    for j in g:
                        dead |= 1 << j
                else:
                    pe *= 1 - c
            law[((1 << n) - 1) ^ dead] += pi * pe
    return law


@pytest.mark.parametrize("seed", range(4))
def test_per_spacecraft_and_groups_against_brute_force(seed):
    rng = np.random.default_rng(seed)
    rows, w = random_rows(seed, c_n=8)
    n = 5
    q = tuple(float(x) for x in rng.uniform(0.01, 0.3, 7))
    beta = float(rng.uniform(0.05, 0.5))
    groups = ((0, 2), (1, 3, 6))                   # member 4 (and 5, 6 when n < 7) alone
    m = FailureModel(p_f=q, beta=beta, groups=groups)
    law = brute_mask_law(q[:n], beta, [(0, 2), (1, 3), (4,)], n)
    assert law.sum() == pytest.approx(1.0, abs=1e-14)
    np.testing.assert_allclose(survivor_weights(m, n).score, law, rtol=1e-13, atol=1e-16)
    sw = sorted(rng.choice(8, n, replace=False).tolist())
    need = float(np.quantile([w[rows[s][sw].any(axis=0)].sum() for s in range(4)], 0.3))
    cov = covered_table(rows, sw, w, need)
    want = float((cov * law).sum(axis=1).mean())
    assert exact(m, rows, sw, w, need) == pytest.approx(want, abs=1e-14)
    # the evaluator flies member k on the k-th grid candidate in increasing order
    assert Evaluator(rows, w, need, m)([sw[::-1]])[0] == pytest.approx(want, abs=1e-14)
    if seed:
        return
    # p_f uncertain on a group model: the law averaged over the prior, by quadrature
    mp = FailureModel(p_f=(0.1,), beta=beta, groups=groups, prior=Prior(mean=0.1, sd=0.05))
    a, b = mp.prior.ab
    quad = [integrate.quad(lambda p: brute_mask_law((p,) * n, beta, [(0, 2), (1, 3), (4,)],
                                                    n)[t] * stats.beta.pdf(p, a, b), 0, 1,
                           epsabs=1e-14, epsrel=1e-12)[0] for t in range(1 << n)]
    np.testing.assert_allclose(survivor_weights(mp, n).score, quad, rtol=1e-9, atol=1e-15)


# ----------------------------------------------------------------- against a direct Monte Carlo
def direct_mc(rng, cov, draws, n, p_sampler, beta, k_lost=0):
    """Success rate of ``draws`` direct draws: a scenario, p_f, the common-cause event over the
    swarm, exactly-k losses, the independent failures; ``cov`` (S, 2^n) the survivors' cover."""
    s = rng.integers(cov.shape[0], size=draws)
    p = p_sampler(draws)
    common = rng.random(draws) < beta * p
    failed = rng.random((draws, n)) < ((1 - beta) * p)[:, None]
    if k_lost:
        perm = np.argsort(rng.random((draws, n)), axis=1)[:, :k_lost]
        np.put_along_axis(failed, perm, True, axis=1)
    failed |= common[:, None]
    mask = ((~failed) * (1 << np.arange(n))).sum(axis=1)
    return cov[s, mask].mean()


@pytest.mark.parametrize("case", ["beta", "prior", "both"])
def test_exact_p_against_a_direct_monte_carlo(case):
    rows, w = random_rows(3, s_n=5, c_n=8, v_n=40, density=0.3)
    sw = [0, 2, 3, 5, 7]
    n = len(sw)
    # a threshold where a common cause and the spread of p_f both move P well beyond the noise
    need = 0.7 * min(w[rows[s][sw].any(axis=0)].sum() for s in range(5))
    cov = covered_table(rows, sw, w, need)
    mean, sd = (0.2, 0.1) if case == "both" else (0.05, 0.02)
    beta = 0.0 if case == "prior" else 0.1
    prior = None if case == "beta" else Prior(mean=mean, sd=sd)
    m = FailureModel(p_f=(mean,), beta=beta, prior=prior)
    rng = np.random.default_rng(41)
    if prior is None:
        sampler = lambda d: np.full(d, mean)                        # noqa: E731
    else:
        sampler = lambda d: rng.beta(*prior.ab, size=d)              # noqa: E731
    draws = 2_000_000
    got = direct_mc(rng, cov, draws, n, sampler, beta)
    want = exact(m, rows, sw, w, need)
    se = math.sqrt(want * (1 - want) / draws)
    assert abs(got - want) < 4 * se, (got, want, se)
    # enough draws to tell a wrong weight: the model without its prior / its common cause
    wrong = exact(FailureModel(p_f=(mean,), beta=0.0 if case == "beta" else beta), rows, sw, w,
                  need) if case != "both" else exact(FailureModel.fixed(mean), rows, sw, w, need)
    assert abs(wrong - got) > 6 * se, (wrong, got, se)


def test_failures_k_is_the_dispersion_draw():
    """Exactly-k losses plus independent p_f: exact P against the Monte Carlo kind's own draw."""
    rows, w = random_rows(5, s_n=3, c_n=8, v_n=30, density=0.4)
    sw = [1, 2, 4, 6, 7]
    n = len(sw)
    need = float(np.median([w[rows[s][sw].any(axis=0)].sum() for s in range(3)])) * 0.8
    cov = covered_table(rows, sw, w, need)
    mc = SimpleNamespace(failures_k=1, failure_probability=0.15, failure_probability_sd=0.0,
                         failure_probability_values=None, common_cause_beta=0.0,
                         common_cause_groups=None, failure_in_pass_share=0.0)
    draws = 60_000
    hits = 0
    for k in range(draws):
        d = failure_dispersion.draw(sample_rng(9, k, 1), n, mc, None, None)
        mask = int((d["active"] * (1 << np.arange(n))).sum())
        hits += cov[k % 3, mask]
    model = failure_dispersion.failure_model(mc)
    want = exact(model, rows, sw, w, need)
    se = math.sqrt(want * (1 - want) / draws)
    assert abs(hits / draws - want) < 4 * se
    ignored = exact(FailureModel.fixed(0.15), rows, sw, w, need)        # failures_k dropped
    assert abs(ignored - want) > 10 * se


def test_sampler_has_the_exact_law():
    """draw_failures (groups, per-spacecraft p_f, a list prior): pattern frequencies against
    the exact survivor law (chi-square)."""
    n = 4
    m = FailureModel(p_f=(0.2,), beta=0.3, groups=((0, 1), (2,)),
                     prior=Prior(values=(0.1, 0.3)))
    rng = np.random.default_rng(5)
    draws = 40_000
    counts = np.zeros(1 << n)
    for _ in range(draws):
        d = draw_failures(m, n, rng.random(n), rng)
        counts[int((d.active * (1 << np.arange(n))).sum())] += 1
    law = survivor_weights(m, n).score
    assert stats.chisquare(counts, law * draws).pvalue > 1e-3
    plain = FailureModel.fixed(0.2)                    # today's draw: u < p_f, nothing else
    u = np.random.default_rng(1).random(n)
    gen = np.random.default_rng(2)
    d = draw_failures(plain, n, u, gen)
    assert np.array_equal(d.failed, u < 0.2) and gen.random() == np.random.default_rng(2).random()


# ----------------------------------------------------------------- the proofs' upper law
def random_model(rng, n):
    kind = rng.integers(4)
    q = tuple(float(x) for x in rng.uniform(0.0, 0.4, n)) if kind in (1, 3) else \
        (float(rng.uniform(0.0, 0.4)),)
    groups = None
    if kind >= 2:
        perm = rng.permutation(n)
        cut = int(rng.integers(1, n))
        groups = (tuple(int(i) for i in perm[:cut]), tuple(int(i) for i in perm[cut:]))
    prior = Prior(values=tuple(rng.uniform(0.0, 0.4, 3))) if len(q) == 1 and rng.random() < 0.4 \
        else None
    return FailureModel(p_f=q, beta=float(rng.uniform(0, 0.6)), groups=groups,
                        in_pass_share=float(rng.choice([0.0, rng.uniform(0, 1)])), prior=prior)


@pytest.mark.parametrize("seed", range(5))
def test_upper_law_bounds_p_from_above(seed):
    """Random rows, random models: score <= true P (losses in the pass drawn) <= upper P,
    and every bound taken from the upper law is above the upper P."""
    rng = np.random.default_rng(seed)
    rows, w = random_rows(seed, s_n=3, c_n=7, v_n=24, density=0.3)
    s_n, c_n = rows.shape[:2]
    for _ in range(6):
        n = int(rng.integers(2, 6))
        model = random_model(rng, n)
        sw = sorted(rng.choice(c_n, n, replace=False).tolist())
        need = float(rng.uniform(0.3, 0.8))
        ev = Evaluator(rows, w, need, model)
        score, up = float(ev([sw])[0]), float(ev.upper([sw])[0])
        assert score <= up + 1e-12
        # the true P with losses in the pass: random first-seen fractions, loss times drawn
        seen = np.where(rows[:, sw], rng.random((s_n, n, rows.shape[2])), np.inf)
        m_draws = 3000
        per = []
        for k in range(m_draws):
            s = k % s_n
            d = draw_failures(model, n, rng.random(n), rng)
            per.append(sample_probabilities(rows[s:s + 1][:, sw], w, need, model, [d],
                                            seen[s:s + 1])[0])
        true = float(np.mean(per))
        se = float(np.std(per)) / math.sqrt(m_draws) + 1e-12
        assert score - 5 * se <= true <= up + 5 * se
        # U_m: the best m-subset's covered fraction of scenarios (brute force)
        u = [0.0]
        for mm in range(1, n + 1):
            u.append(max(np.mean([w[rows[s][list(c)].any(axis=0)].sum() >= need - 1e-12
                                  for s in range(s_n)])
                         for c in itertools.combinations(range(c_n), mm)))
        assert level_bound(n, u, model) >= up - 1e-12
        base, one = screen_terms(n, u, model)
        sws = survivor_weights(model, n)
        for mask in range(1 << n):                      # the envelope bounds every set
            k = bin(mask).count("1")
            assert sws.envelope[k] >= (sws.proof[mask] if not sws.exchangeable
                                       else sws.proof[k]) - 1e-15
        assert count_envelope(model, n).shape == (n + 1,)
        # per scenario: the down-set bound with the true N0 and k* is above the upper P
        for s in range(s_n):
            one_s = rows[s:s + 1]
            cover = lambda c: bool(c) and w[one_s[0][list(c)].any(axis=0)].sum() >= need - 1e-12  # noqa: E731
            n0 = next((mm for mm in range(1, c_n + 1)
                       if any(cover(c) for c in itertools.combinations(range(c_n), mm))), c_n + 1)
            ks = None
            for kk in range(1, n + 1):
                tolerant = any(all(cover(set(c) - set(f)) for f in itertools.combinations(c, kk))
                               for c in itertools.combinations(range(c_n), n))
                if not tolerant:
                    ks = kk
                    break
            p_s = float(Evaluator(one_s, w, need, model).upper([sw])[0])
            assert downset_bound(n, model, n0, ks) >= p_s - 1e-12


# ----------------------------------------------------------------- the designer with a model
@pytest.mark.parametrize("budget", [0, 20000])     # bounds and searches; every swarm scored
@pytest.mark.parametrize("model,p", [
    (FailureModel(p_f=(0.1,), beta=0.1), 0.6),
    (FailureModel(p_f=(0.05,), prior=Prior(mean=0.05, sd=0.02)), 0.6),
    (FailureModel(p_f=(0.05, 0.2, 0.05, 0.1, 0.3, 0.05, 0.1), beta=0.2, groups=((0, 1), (2, 3))),
     0.6),
    (FailureModel(p_f=(0.1,), failures_k=1), 0.6),
    (FailureModel(p_f=(0.1,), in_pass_share=0.5), 0.6),
    # 4-swarms score below p but reach it in the upper law: size 4 must stay unresolved
    (FailureModel(p_f=(0.1,), in_pass_share=0.5), 0.75),
])
def test_designer_answers_as_exhaustive_search(model, p, budget):
    """Every swarm scored by brute force: the designer's N meets p, and every proof of a
    smaller size holds (no swarm of it reaches p even under the upper law)."""
    rows, w = random_rows(11, s_n=4, c_n=9, v_n=30, density=0.35)
    need = 0.9
    res = min_swarm_reliable(rows, w, p=p, p_f=model, need=need, n_max=7, sep_steps=0,
                             enumerate_budget=budget)
    ev = Evaluator(rows, w, need, model)
    got = ev([res.indices])[0]
    assert got >= p - 1e-12 and got == pytest.approx(res.probability, abs=1e-12)
    best = {n: ev.upper(all_swarms(9, n, 0)).max() for n in range(1, res.n)}
    for n in range(1, int(res.bound)):
        assert best[n] < p                    # proven sizes are truly short
    if res.status == "optimal":
        assert all(best[n] < p for n in range(1, res.n))


def test_errors_name_the_field():
    ok = dict(failures_k=0, failure_probability=0.05, failure_probability_sd=0.0,
              failure_probability_values=None, common_cause_beta=0.0,
              common_cause_groups=None, failure_in_pass_share=0.0)
    bad = [({"failure_probability": [0.1, 1.5]}, "failure_probability", "item 1"),
           ({"failure_probability": "x"}, "failure_probability", "a number or a list"),
           ({"failure_probability_sd": 0.5}, "failure_probability_sd", "too wide"),
           ({"failure_probability_values": [0.1], "failure_probability": 0.2},
            "failure_probability", "replaced"),
           ({"common_cause_groups": [[0, 1], [1]]}, "common_cause_groups", "two groups"),
           ({"common_cause_groups": [[0], [2]], "common_cause_beta": 0.1, "failures_k": 1},
            "failures_k", "not supported"),
           ({"failure_probability": [0.1, 0.2], "failure_probability_sd": 0.01},
            "failure_probability", "one value")]
    for change, field, words in bad:
        mc = SimpleNamespace(**{**ok, **change})
        with pytest.raises(InputError) as e:
            failure_dispersion.check(mc)
        assert e.value.field == field and words in e.value.message, e.value
    with pytest.raises(InputError) as e:
        failure_dispersion.check_fleet(SimpleNamespace(**{**ok, "failure_probability":
                                                          [0.1, 0.2]}), 5, "design.n_max")
    assert e.value.field == "failure_probability"
    assert FailureDraw  # the record the Monte Carlo kind and the validation share
    assert independent_weights(0.1, 3).size == 4


def test_model_draws_shift_no_other_dispersion():
    """A common cause and an uncertain p_f draw beside the dispersions' shared stream
    (seeds.side_rng): the misalignment drawn after the failures keeps its numbers, and a
    plain model keeps today's losses."""
    import dataclasses

    from ideas_hpc.campaign.schema.campaign_tables import load
    from ideas_hpc.campaign.setup import setup_from_campaign
    from ideas_hpc.montecarlo.dispersions import draw_sample

    from test_campaign_mc import MC, SHORT

    THETA = np.array([0.2, 1.7, 2.4])
    c = load(MC, SHORT)
    setup = setup_from_campaign(c)
    mc = dataclasses.replace(c.config.monte_carlo, failure_probability=0.2, failures_k=0,
                             sigma_misalignment_rad=1e-3)
    more = dataclasses.replace(mc, common_cause_beta=0.5, failure_probability_sd=0.1)
    for k in range(40):
        a, _ = draw_sample(mc, 5, k, THETA, setup)
        b, _ = draw_sample(more, 5, k, THETA, setup)
        np.testing.assert_array_equal(a["misalignment_prv"], b["misalignment_prv"])
        rng = sample_rng(5, k, 1)                      # today's draw, written out
        rng.standard_normal(3), rng.uniform(0.0, 1.0)      # gravity, reflectivity
        rng.standard_normal((THETA.size, 3)), rng.standard_normal((THETA.size, 3))  # state
        rng.permutation(THETA.size)
        np.testing.assert_array_equal(a["active"], rng.uniform(0.0, 1.0, THETA.size) >= 0.2)


def test_every_model_parameter_has_its_key():
    """Errors of the model name the campaign's keys: every parameter is mapped."""
    import dataclasses

    names = {f.name for f in dataclasses.fields(FailureModel)} - {"prior"}
    assert names | {"p_f_sd", "p_f_values"} == set(failure_dispersion.FIELDS)
    keys = {k for k, _ in failure_dispersion.FAILURE_KEYS}
    assert set(failure_dispersion.FIELDS.values()) <= keys
