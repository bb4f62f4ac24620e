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
per scenario it never undercounts; for n = 2 the subsets are single members,
each judged on its one gap, the whole ring but itself). Every X that could reach p is therefore
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

Every proof here holds under the assumptions listed in :func:`screen_size`
(the failure model of :mod:`ideas_hpc.design.reliability_stats`, proven
``Ubar_k`` of separated swarms, the relaxation's rounding, the comparison
tolerance, n >= 2); where one fails, or a cap or the deadline cuts the work,
the outcome is a search, never a proof (issue 41: a one-member list once came
back empty and "complete", and N = 2 was proven short where a 2-swarm met p).

The relaxation needs every scenario's gap matrix ``M_s`` on the full grid
(:func:`ideas_hpc.design.ring_bound.ring_bound`): ``Mt[i, d, s]``, entries
above the slack set to ``+inf`` and the rest rounded down to float32.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.core.design.ring_screen import relaxed_weighted, screen_swarms
from ideas_hpc.design.reliability_stats import P_TOL, proof_model
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
#: Margin below ``p - P_TOL`` kept by the relaxed filter: the relaxed and the exact
#: probability are different float sums of the same terms.
FLOAT_SLACK = 1e-12


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
    route: str = ""             # which return path of screen_size (its docstring)


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


def _check_inputs(mt, slack, n: int, p: float, u_bar, m: int) -> np.ndarray:
    """``u_bar`` as float64 after the checks every proof of :func:`screen_size` rests on
    (``InputError`` naming the parameter otherwise)."""
    if int(n) != n or n < 2:
        raise InputError(f"the screen settles sizes n >= 2 (its proof bounds the "
                         f"(n - 1)-subsets of a swarm), got {n!r}", field="n")
    if mt.ndim != 3 or mt.dtype != np.float32:
        raise InputError("must be the (K, D, S) float32 of `stack_gap_matrices`", field="mt")
    sl = np.asarray(slack)
    if sl.shape != (mt.shape[2],) or not np.all(np.isfinite(sl)):
        raise InputError(f"needs one finite slack per scenario ({mt.shape[2]})", field="slack")
    if not 0.0 < p <= 1.0:
        raise InputError(f"must be in (0, 1], got {p!r}", field="p")
    if int(m) != m or m < 0:
        raise InputError(f"must be an integer >= 0, got {m!r}", field="m")
    u = np.asarray(u_bar, dtype=np.float64).ravel()
    if u.size < n + 1 or np.any(~(u[:n + 1] >= 0.0)):
        raise InputError(f"needs n + 1 = {n + 1} bounds >= 0 (U_0 .. U_n)", field="u_bar")
    return u


def _search(n: int, route: str, screened: int = 0, checked: int = 0, best=(None, 0.0)):
    """A search outcome: n is neither proven short nor met (``best`` the best exact P seen)."""
    return ScreenOutcome(n=n, proven_short=False, swarm=None, probability=best[1], upper=1.0,
                         screened=screened, checked=checked, route=route)


def screen_size(mt, slack, ev, n: int, p: float, p_f: float, u_bar: list, m: int,
                deadline_ok=lambda: True) -> ScreenOutcome:
    """Settle size n on the bank when possible (module docstring).

    Assumptions of the proof (``proven_short``), each enforced or stated:

    * the failure model of :mod:`ideas_hpc.design.reliability_stats` (checked by
      :func:`~ideas_hpc.design.reliability_stats.proof_model`): the grouping by the
      number lost uses the model's heaviest set of each size (exact for an exchangeable
      model) and its upper model (an in-pass loss counted as a survival); a model with
      no single-loss weight (``p_f`` of 0 or 1) gives the search only
      (``route="model"``), as does an ``ev`` of another model; a size whose best
      upper-model P checked reaches p gives the search (``route="upper_model"``);
    * ``u_bar[k]`` bounds ``U_k``, the best fraction of scenarios a *separated*
      k-swarm covers (at the evaluator's tolerance), for k = 0 .. n; ``m`` is the
      same separation (``InputError`` when ``u_bar`` is short or negative);
    * ``mt`` and ``slack`` are the relaxation of
      :mod:`ideas_hpc.core.design.ring_screen` on the same bank, need and grid as
      ``ev`` (entries rounded down, one row per grid candidate; ``slack`` is
      ``reach_s - need`` and :data:`SLACK_TOL` is added here): the counts then
      never undercount, for (n - 1)-subsets of every size, one member included;
    * coverage monotone (a subset never covers more): the relaxed probability
      bounds the exact one;
    * "reaches p" means ``P >= p - P_TOL`` (the designer's comparison): the
      threshold on the subsets is computed from ``p - P_TOL`` and the relaxed
      filter keeps a further :data:`FLOAT_SLACK` below it;
    * ``n >= 2`` (``InputError`` otherwise: the bound is on (n - 1)-subsets;
      :meth:`~ideas_hpc.design.reliability.ReliabilityDesigner.screen` returns None
      for n = 1 and the designer settles it by its other routes: the level bound,
      the enumeration of the K candidates).

    A proof is returned only when the list of (n - 1)-swarms is complete (no cap,
    no node limit), every extension at or above p by the relaxation was scored
    exactly (no :data:`EXACT_CAP`) and ``deadline_ok`` never said False; any of
    those stops gives a search outcome (``proven_short`` False), never a proof.

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
        False once the design's time is up (checked after the listing and between
        the exact batches).

    Returns
    -------
    ScreenOutcome
        ``route`` says which return path: ``"level"`` (proof: not even every
        subset at full count reaches p), ``"screen"`` (proof: the complete list
        extended and scored), ``"found"`` (a swarm at p), or a search that
        settled nothing: ``"model"``, ``"no_pruning"`` (the bound on the subsets
        excludes none), ``"screen_cap"`` / ``"screen_nodes"`` (the listing was cut:
        the (n - 1)-swarms of most scenarios in it, if any, were extended and none
        reached p), ``"extend_cap"`` (a complete list too long to extend: the same
        search pool), ``"exact_cap"``, ``"deadline"``, ``"upper_model"``.
    """
    u_bar = _check_inputs(mt, slack, n, p, u_bar, m)
    k_n, _, s_n = mt.shape
    model = proof_model(p_f)
    ev_model = getattr(ev, "model", model)
    base, one = screen_terms(n, u_bar, model)
    # no single-loss term to bound (p_f of 0 or 1), or an evaluator of another model:
    # the grouping by the number lost proves nothing here
    if not one > 0.0 or ev_model != model:
        return _search(n, "model")
    # X meets p when P(X) >= p - P_TOL: the subsets' threshold keeps every such X
    r = (p - P_TOL - base) / one
    if r <= 0.0:
        return _search(n, "no_pruning")
    # T reaches thr scenarios: sum_i U(X - x_i) <= n (thr - 1) / S < R for X without one
    thr = max(1, int(math.ceil(s_n * r / n - 1e-9)))
    if thr > s_n:
        return ScreenOutcome(n=n, proven_short=True, swarm=None, probability=0.0,
                             upper=base + one * n, screened=0, checked=0, route="level")
    sl = np.asarray(slack, dtype=np.float64) + SLACK_TOL
    found, counts, listed = screen_swarms(mt, sl, n - 1, int(m), thr, SCREEN_CAP, SCREEN_NODES,
                                          _spread_step(k_n))
    cut = "screen_cap" if found.shape[0] > SCREEN_CAP else "screen_nodes"
    complete = listed and found.shape[0] * k_n <= EXTEND_CAP
    if not deadline_ok():
        return _search(n, "deadline", found.shape[0])
    if complete:
        pool = found
    elif found.shape[0] == 0:
        return _search(n, cut)
    else:           # the (n - 1)-swarms of most scenarios, spread over the list
        top = np.flatnonzero(counts == counts.max())
        pool = found[top[np.linspace(0, top.size - 1, min(SEARCH_POOL, top.size)).astype(int)]]
    why = "extend_cap" if listed else cut
    xs = _extensions(pool, k_n, int(m))
    relaxed = relaxed_weighted(mt, sl, np.ascontiguousarray(xs), count_envelope(p_f, n)) \
        if xs.shape[0] else np.zeros(0)
    # the relaxed and exact sums round differently: keep a float margin below the level
    level = p - P_TOL - FLOAT_SLACK
    order = np.argsort(-relaxed, kind="stable")
    order = order[relaxed[order] >= level]
    best = (None, 0.0)
    best_up = 0.0       # largest upper-model P checked (losses in the pass as survivals)
    checked = 0
    for lo in range(0, order.size, 256):
        if checked >= EXACT_CAP or not deadline_ok():
            why = "exact_cap" if checked >= EXACT_CAP else "deadline"
            complete = False
            break
        idx = order[lo:lo + 256]
        vals, ups = ev.with_upper(xs[idx])
        best_up = max(best_up, float(ups.max()))
        checked += idx.size
        i = int(np.argmax(vals))
        if vals[i] > best[1]:
            best = (xs[idx[i]], float(vals[i]))
        if vals[i] >= p - P_TOL:
            return ScreenOutcome(n=n, proven_short=False, swarm=xs[idx[i]],
                                 probability=float(vals[i]), upper=1.0,
                                 screened=found.shape[0], checked=checked, route="found")
    if not complete:
        return _search(n, why, found.shape[0], checked, best)
    if best_up >= p - P_TOL:    # an in-pass loss counted as survival would reach p
        return _search(n, "upper_model", found.shape[0], checked, best)
    below = relaxed[relaxed < level]
    ub = max(base + one * n * (thr - 1) / s_n, best_up,
             float(below.max()) if below.size else 0.0)
    return ScreenOutcome(n=n, proven_short=True, swarm=None, probability=best[1], upper=ub,
                         screened=found.shape[0], checked=checked, route="screen")


def screen_note(proved, found) -> str:
    """What the screen settled (sizes ``proved`` short of p, sizes ``found`` met), in one
    note of the design."""
    parts = []
    if proved:
        parts.append(f"sizes {sorted(proved)} proven short of p")
    if found:
        parts.append(f"sizes {sorted(found)} met by a swarm found")
    return (" and ".join(parts) + " by the screen over all scenarios (every swarm that could "
            "reach p is one of the (N-1)-swarms the ring-gap relaxation lets cover enough "
            "scenarios plus one member, ideas_hpc.design.screen_bound)")
