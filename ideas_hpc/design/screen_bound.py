"""Settle one swarm size on a large bank: screen, extend, check (issue 29, proof at scale).

For a swarm X of n members, failures independent with probability ``p_f``,
``q = 1 - p_f``, group the bank probability by the number of failures::

    P(X) = q^n U(X) + p_f q^(n-1) sum_i U(X - x_i) + sum_{j>=2} (j failures)

(any failure model, issue 41: ``q^n`` and ``p_f q^(n-1)`` become the envelope weights
``env_n``, ``env_{n-1}`` of the upper model and the binomial sums its counts,
:func:`ideas_hpc.failures.sums.screen_terms`; exact for an exchangeable model, and an
upper bound set by set otherwise, so every step below holds)

where ``U(T)`` is the fraction of scenarios the survivors T cover. Bound the
first and last parts by ``Ubar_n`` and ``Ubar_{n-j}`` (the level bound of
:mod:`ideas_hpc.design.reliability`). Then X reaches p only if

    sum_i U(X - x_i) >= R = (p - q^n Ubar_n - rest) / (p_f q^(n-1)),

so at least one of its n subsets of n - 1 covers a fraction ``R / n`` of the
scenarios. Those (n - 1)-swarms are *screened* by the ring-gap relaxation over
all scenarios at once (:func:`ideas_hpc.core.design.ring_screen.screen_swarms`:
per scenario it never undercounts). Every X that could reach p is therefore
one of them plus one member. Each such X is scored by the relaxed probability
(:func:`~ideas_hpc.core.design.ring_screen.relaxed_weighted`, never below
the exact one), and those at or above p by the exact ``P_bank``:

* an X with exact ``P_bank >= p`` is a swarm of n that meets p (the search);
* when the screen listed every candidate (not over :data:`SCREEN_CAP`) and no
  X reaches p exactly, no n-swarm does: n is proven short of p (the proof), with
  ``UB(n) = max(exact P of those checked, q^n Ubar_n + rest + p_f q^(n-1) n
  (thr - 1) / S)``.

When the screen finds more than the cap, only the search part runs, on
:data:`SEARCH_POOL` of the (n - 1)-swarms with the most scenarios; it can
still settle n by finding a swarm (the built-in ellipsoid's main job: many
3-swarms cover every scenario, and a 4-swarm at ``0.95^4 + 2 x 0.05 x 0.95^3 =
0.9002`` is one of them plus a neighbour, which the swap search did not find).

The relaxation needs every scenario's gap matrix ``M_s`` on the full grid
(:func:`ideas_hpc.design.ring_bound.ring_bound`): ``Mt[i, d, s]``, entries
above the slack set to ``+inf`` and the rest rounded down to float32.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.core.design.ring_screen import relaxed_weighted, screen_swarms
from ideas_hpc.failures.sums import count_envelope, screen_terms

#: Most (n - 1)-swarms the screen lists before it gives up the proof.
SCREEN_CAP = 4000
#: Most members the screen's search tries (about a second or two per 10^6 on 256
#: scenarios): it keeps the screen within a design's time limit on large swarms.
SCREEN_NODES = 2_000_000
#: Most extensions X scored by the relaxation in proof mode (candidates x members).
EXTEND_CAP = 200_000
#: (n - 1)-swarms extended in search-only mode (the screen found too many).
SEARCH_POOL = 48
#: Most X evaluated exactly per size.
EXACT_CAP = 2000
#: Largest ``Mt`` kept (bytes).
MAX_BYTES = 1 << 30
#: Tolerance added to the slack: the evaluator counts coverage >= need - 1e-12 and
#: the gap sums add float rounding.
SLACK_TOL = 1e-9


def clip_gap_matrix(M: np.ndarray, slack: float) -> np.ndarray:
    """(K, D) float32 of one scenario's ``M[i, d]`` (module docstring): rounded down,
    ``+inf`` where above ``slack``; ``D`` the first d at which every arc fails, at least 1."""
    M = np.asarray(M, dtype=np.float64)
    out = M.astype(np.float32)
    up = out.astype(np.float64) > M
    out[up] = np.nextafter(out[up], np.float32(0.0))
    out[M > slack] = np.inf
    live = np.isfinite(out).any(axis=0)
    d_n = int(np.flatnonzero(live)[-1]) + 1 if live.any() else 1
    return out[:, :d_n]


def stack_gap_matrices(clipped: list) -> np.ndarray | None:
    """``Mt[i, d, s]`` from the scenarios' clipped matrices (None when over :data:`MAX_BYTES`)."""
    k = clipped[0].shape[0]
    d_n = max(c.shape[1] for c in clipped)
    if k * d_n * len(clipped) * 4 > MAX_BYTES:
        return None
    mt = np.full((k, d_n, len(clipped)), np.inf, dtype=np.float32)
    for s, c in enumerate(clipped):
        mt[:, :c.shape[1], s] = c
    return mt


@dataclass
class ScreenOutcome:
    """What :func:`screen_size` settled about size n."""

    n: int
    proven_short: bool          # no n-swarm reaches p (the proof)
    swarm: np.ndarray | None    # an n-swarm with exact P_bank >= p (the search), or None
    probability: float          # its exact P_bank (0 when none)
    upper: float                # proven UB(n) when proven_short, else 1
    screened: int               # (n - 1)-swarms listed (SCREEN_CAP + 1: too many)
    checked: int                # swarms evaluated exactly


def _spread_step(k: int) -> int:
    """A step coprime with k near k / golden ratio: its multiples visit the ring evenly."""
    step = max(1, int(round(k / 1.618033988749895)))
    while math.gcd(step, k) != 1:
        step += 1
    return step % k or 1


def _extensions(base: np.ndarray, k: int, m: int) -> np.ndarray:
    """Every sorted (n)-swarm ``T + x`` of the (n - 1)-swarms ``base``, gaps > ``m``."""
    ring = np.arange(k)
    out = []
    for t in base:
        d = np.abs(ring[:, None] - t[None, :])
        ok = (np.minimum(d, k - d) > m).all(axis=1)
        xs = ring[ok]
        if xs.size:
            out.append(np.sort(np.c_[np.repeat(t[None, :], xs.size, axis=0), xs], axis=1))
    if not out:
        return np.zeros((0, base.shape[1] + 1), dtype=np.int64)
    return np.unique(np.concatenate(out), axis=0)


def screen_size(mt, slack, ev, n: int, p: float, p_f: float, u_bar: list, m: int,
                deadline_ok=lambda: True) -> ScreenOutcome:
    """Settle size n on the bank when possible (module docstring).

    Parameters
    ----------
    mt : (K, D, S) float32
        :func:`stack_gap_matrices`.
    slack : (S,) float64
        ``reach_s - need`` per scenario.
    ev : :class:`~ideas_hpc.design.reliability.Evaluator`
        Exact ``P_bank``.
    n : int
        Swarm size (>= 2).
    p : float
        Level.
    p_f : float or FailureModel
        Failure probability, or the failure model (:mod:`ideas_hpc.failures`).
    u_bar : list
        ``u_bar[k]`` proven bounds on ``U_k``, k = 0 .. n.
    m : int
        Separation (grid steps).
    deadline_ok : callable
        False once the design's time is up (checked between the exact batches).
    """
    k_n, _, s_n = mt.shape
    base, one = screen_terms(n, u_bar, p_f)
    r = (p - base) / one
    none = ScreenOutcome(n=n, proven_short=False, swarm=None, probability=0.0, upper=1.0,
                         screened=0, checked=0)
    if n < 2 or r <= 0.0:
        return none
    # T reaches thr scenarios: sum_i U(X - x_i) <= n (thr - 1) / S < R for X without one
    thr = max(1, int(math.ceil(s_n * r / n - 1e-9)))
    if thr > s_n:
        return ScreenOutcome(n=n, proven_short=True, swarm=None, probability=0.0,
                             upper=base + one * n, screened=0, checked=0)
    sl = np.asarray(slack, dtype=np.float64) + SLACK_TOL
    found, counts, listed = screen_swarms(mt, sl, n - 1, int(m), thr, SCREEN_CAP, SCREEN_NODES,
                                          _spread_step(k_n))
    complete = listed and found.shape[0] * k_n <= EXTEND_CAP
    if complete:
        pool = found
    elif found.shape[0] == 0:
        return none
    else:           # the (n - 1)-swarms of most scenarios, spread over the list
        top = np.flatnonzero(counts == counts.max())
        pool = found[top[np.linspace(0, top.size - 1, min(SEARCH_POOL, top.size)).astype(int)]]
    xs = _extensions(pool, k_n, int(m))
    relaxed = relaxed_weighted(mt, sl, np.ascontiguousarray(xs), count_envelope(p_f, n)) \
        if xs.shape[0] else np.zeros(0)
    order = np.argsort(-relaxed, kind="stable")
    order = order[relaxed[order] >= p - 1e-12]
    best = (None, 0.0)
    best_up = 0.0       # largest upper-model P checked (losses in the pass as survivals)
    checked = 0
    for lo in range(0, order.size, 256):
        if checked >= EXACT_CAP or not deadline_ok():
            complete = False
            break
        idx = order[lo:lo + 256]
        vals, ups = ev.with_upper(xs[idx])
        best_up = max(best_up, float(ups.max()))
        checked += idx.size
        i = int(np.argmax(vals))
        if vals[i] > best[1]:
            best = (xs[idx[i]], float(vals[i]))
        if vals[i] >= p - 1e-12:
            return ScreenOutcome(n=n, proven_short=False, swarm=xs[idx[i]],
                                 probability=float(vals[i]), upper=1.0,
                                 screened=found.shape[0], checked=checked)
    if not complete or best_up >= p - 1e-12:
        return ScreenOutcome(n=n, proven_short=False, swarm=None, probability=best[1],
                             upper=1.0, screened=found.shape[0], checked=checked)
    below = relaxed[relaxed < p - 1e-12]
    ub = max(base + one * n * (thr - 1) / s_n, best_up,
             float(below.max()) if below.size else 0.0)
    return ScreenOutcome(n=n, proven_short=True, swarm=None, probability=best[1], upper=ub,
                         screened=found.shape[0], checked=checked)
