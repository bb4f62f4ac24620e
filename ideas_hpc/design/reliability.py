"""The fewest spacecraft that reach a coverage threshold with probability >= p (issue 20).

On a scenario bank (``rows[s, c, v]``: vertex v seen or mapped by grid
candidate c in scenario s, S draws of the continuous dispersions), the
probability of a swarm is the scenario mean of its exact failure-weighted
success probability (:mod:`ideas_hpc.core.design.reliability`: the survivor
sets T are enumerated, not sampled, each weighted by ``pi(T)`` of the failure
model, :mod:`ideas_hpc.failures`; independent failures:
``pi(T) = (1-p_f)^|T| p_f^(N-|T|)``)::

    P_bank(swarm) = (1/S) sum_s sum_{T subset swarm} pi(T) 1[cov_s(T) >= need]

With losses in the pass the bank scores them as whole-pass losses (a lower bound,
:mod:`ideas_hpc.design.reliability_eval`) and every proof below takes the upper
model (those losses counted as survivals), so "proven short of p" holds for the
true P.

:func:`min_swarm_reliable` proves the fewest N with ``P_bank >= p``:

* **Infeasibility.** ``U_m``, the largest fraction of scenarios an m-swarm
  reaches with no failure, has a proven upper bound ``Ubar_m`` from the
  scenario-indicator programme (:mod:`ideas_hpc.design.scenario_mip`) and
  the fraction of scenarios whose ring-gap bound allows m (the only one on
  banks above :data:`MIP_MAX_CELLS`). The
  survivors of any N-swarm after j failures are an (N-j)-swarm, so every
  N-swarm has ``P <= UB(N) = sum_j P(j lost) Ubar_{N-j}``
  (:func:`~ideas_hpc.failures.sums.level_bound`; ``C(N,j) p_f^j (1-p_f)^(N-j)`` for
  independent failures); N is
  infeasible when ``UB(N) < p``. The per-scenario failure-tolerance bound
  (:mod:`ideas_hpc.design.tolerance_bound`: no N-swarm survives every k-failure when
  the k-tolerant minimum exceeds N) tightens ``UB(N)`` on banks of few scenarios.
* **Feasibility.** A swarm of N whose exact ``P_bank >= p``: the programme's
  swarm and the previous size's best swarm plus its best new member, each
  improved by a swap search on the exact ``P_bank`` (:func:`improve`). When
  the number of N-swarms is small (``enumerate_budget``, and at most
  :data:`ENUM_CELLS` swarm-scenarios) every one is scored instead, which settles N
  either way. On a sampled bank (S > 1) the screen of
  :mod:`ideas_hpc.design.screen_bound` tries each size before the programme refines
  ``Ubar_m``, which can spend the whole time limit on one m.

Sizes neither proven infeasible nor met are *unresolved*: the proven lower
bound is the smallest of them, the gap ``(N - bound) / N``, and the status
``optimal`` (gap 0), ``time_limit`` (a programme stopped at the limit) or
``feasible``. Separation: candidates closer than ``m`` grid steps never fly
together (:func:`ideas_hpc.design.bank.conflict_windows`).
"""

from __future__ import annotations

import math
import time

import numpy as np

from ideas_hpc.base import progress
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.vertex_weights import normalised
from ideas_hpc.design.bank import CandidateBank, reduce_problem
from ideas_hpc.design.reliability_eval import N_ENUM_MAX, Evaluator  # noqa: F401 (their old home)
from ideas_hpc.design.reliability_search import all_swarms, extend, improve
from ideas_hpc.failures.model import as_model
from ideas_hpc.failures.sums import level_bound, weights_of
from ideas_hpc.design.ring_bound import ring_bound
from ideas_hpc.design.scenario_mip import ScenarioMIP
from ideas_hpc.design.screen_bound import (clip_gap_matrix, screen_note, screen_size,
                                          stack_gap_matrices)
from ideas_hpc.design.tolerance_bound import ToleranceBound
from ideas_hpc.design.settings import ReliableResult, ReliableSettings  # noqa: F401 (its old home)

#: Largest bank (scenarios x candidates) given to the scenario programme: above it
#: HiGHS does not return within its time limit (eros001708, 5 scenarios x 720
#: candidates: no incumbent, 100 s for a 20 s limit), and ``Ubar_m`` comes from the
#: per-scenario ring-gap bounds alone (still proven; the gap says what is left).
MIP_MAX_CELLS = 5000
#: Most swarm-scenarios one exhaustive enumeration scores (about 25 us each at 642
#: vertices); the quick campaign's 4005 2-swarms x 100 scenarios stay enumerated, a bank
#: of 100 worlds x 45 candidates leaves its 14190 3-swarms (30-47 s) to the screen (16 s).
ENUM_CELLS = 1_000_000




class ReliabilityDesigner:
    """Shared state of one design: the evaluator, the programme and the bounds found so far."""

    def __init__(self, rows, areas, *, need: float, p_f, sep_steps: int = 0,
                 time_limit: float | None = None, enumerate_budget: int = 20000,
                 bound_solver=None, tolerance_solver=None):
        rows = np.asarray(rows, dtype=bool)    # areas (V,) shared or (S, V) per scenario
        self.ev = Evaluator(rows, normalised(areas, rows.shape[0]), need, p_f)
        self.s_n, self.c_n = rows.shape[0], rows.shape[1]
        self.m, self.model = int(sep_steps), as_model(p_f)
        self.t0 = time.perf_counter()
        self.deadline = None if time_limit is None else self.t0 + float(time_limit)
        self.budget = int(enumerate_budget)
        self._mip = None
        self._solver = bound_solver
        self.u_bar = {0: 0.0}
        self.bound_status: dict = {}
        self.mip_swarm: dict = {}
        self.best: dict = {}
        self.exhausted: set = set()
        self.exhausted_upper: dict = {}   # n -> largest upper-model P of every n-swarm
        self._lows = None
        self._tol = None
        self.tol_proved: set = set()
        self._tol_solver = tolerance_solver
        self._clipped: list = []      # per scenario: clipped gap matrix (screen_bound)
        self._slack: list = []
        self._mt = None
        self.screen_proved: set = set()
        self.screen_found: set = set()
        self.settled = False      # the search is over: best_of runs without the clock

    def ring_lows(self, n_max: int) -> np.ndarray:
        """(S,) proven lower bound on each scenario's fewest covering spacecraft (ring-gap
        bound, :mod:`ideas_hpc.design.ring_bound`; ``n_max + 1``: none of ``n_max`` covers)."""
        if self._lows is None:
            lows = np.ones(self.s_n, dtype=np.int64)
            step = 2 * math.pi / self.c_n
            for s in progress.steps(range(self.s_n), "ring-gap bounds", unit="scenario"):
                if self.out_of_time():   # the rest keep the trivial bound 1 (still proven)
                    break
                areas = self.ev.w_of(s)      # each scenario's bound with its own weights
                bank = CandidateBank(theta=step * np.arange(self.c_n), masks=self.ev.rows[s],
                                     areas=areas, step_rad=step, d_sep_m=1.0)
                red = reduce_problem(bank.masks, areas, merge_candidates=False)
                rb = ring_bound(bank, red, self.m, int(n_max), self.ev.need)
                if rb is not None:
                    low = rb.n_bound(self.ev.need)
                    lows[s] = int(n_max) + 1 if low is None else max(1, low)
                    # the screen's relaxation over all scenarios (screen_bound)
                    self._clipped.append(clip_gap_matrix(rb.M, rb.reach - self.ev.need))
                    self._slack.append(rb.reach - self.ev.need)
            self._lows = lows
        return self._lows

    def screen(self, n: int, p: float):
        """Settle size n by the screen of :mod:`ideas_hpc.design.screen_bound` (None when
        the ring-gap matrices are missing: a grid above the ring bound's, or time ran out;
        or when its proof does not apply: n < 2).
        Fed ``u_bar[k] = min(cheap_ubar(k), Ubar_k)``, bounds on separated k-swarms."""
        if n < 2:
            return None
        if self._mt is None:
            if len(self._clipped) != self.s_n or self.out_of_time():
                return None
            self._mt = stack_gap_matrices(self._clipped)
            self._clipped = []
            if self._mt is None:
                return None
        u = [0.0] + [min(self.cheap_ubar(k), self.u_bar.get(k, 1.0)) for k in range(1, n + 1)]
        progress.note(f"screen, N = {n}: every {n - 1}-swarm the ring-gap relaxation lets "
                      f"cover enough of the {self.s_n} scenarios, plus one member")
        return screen_size(self._mt, np.asarray(self._slack), self.ev, n, p, self.model, u,
                           self.m, deadline_ok=lambda: not self.out_of_time())

    def cheap_ubar(self, m: int) -> float:
        """``U_m <=`` the fraction of scenarios whose ring-gap bound allows m spacecraft
        (proven under :meth:`~ideas_hpc.design.ring_bound.RingBound.n_bound`'s conditions,
        with the design's separation; 1 before :meth:`ring_lows`)."""
        return float(np.mean(self._lows <= m)) if self._lows is not None else 1.0

    def left(self):
        return None if self.deadline is None else max(1e-3, self.deadline - time.perf_counter())

    def ubar(self, m: int) -> float:
        if m not in self.u_bar and self._solver is None and self.s_n * self.c_n > MIP_MAX_CELLS:
            self.u_bar[m] = self.cheap_ubar(m)
            self.bound_status[m] = "ring_bound"
        if m not in self.u_bar:
            if self._solver is not None:
                b = self._solver(m, self.left())
            else:
                if self._mip is None:
                    self._mip = ScenarioMIP(self.ev.rows, self.ev.w, self.ev.need, self.m)
                b = self._mip.solve(m, self.left())
            self.u_bar[m] = b.upper / self.s_n
            self.bound_status[m] = b.status
            if b.swarm is not None and b.swarm.size:
                self.mip_swarm[m] = b.swarm
        return self.u_bar[m]

    def tolerance(self) -> ToleranceBound:
        """The per-scenario failure-tolerance bound (:mod:`ideas_hpc.design.tolerance_bound`)."""
        if self._tol is None:
            lows = self._lows if self._lows is not None else np.ones(self.s_n, np.int64)
            self._tol = ToleranceBound(self.ev.rows, self.ev.w, self.ev.need, lows,
                                       2 * math.pi / self.c_n, solver=self._tol_solver)
        return self._tol

    def upper(self, n: int, p: float | None = None, *, refine: bool = True) -> float:
        """Proven ``UB(n)`` (module docstring). The ring-gap fractions first, then the
        per-scenario failure-tolerance bound; the programme refines ``Ubar_m`` from
        ``m = n`` down only while ``UB(n) >= p`` (and ``refine``)."""
        u = [0.0] + [min(self.cheap_ubar(k), self.u_bar.get(k, 1.0)) for k in range(1, n + 1)]
        ub = level_bound(n, u, self.model)
        if ub >= (p if p is not None else 0.0) - 1e-12:
            # with p: solve what could prove n short of p; without: what is known
            tol = self.tolerance().upper(n, self.model, self.deadline, p, solve=p is not None)
            if p is not None and tol < p - 1e-12 <= ub - 1e-12:
                self.tol_proved.add(n)
            ub = min(ub, tol)
        for k in range(n, 0, -1):
            if not refine or (p is not None and ub < p - 1e-12) or u[k] == 0.0 \
                    or self.out_of_time():
                break
            u[k] = min(u[k], self.ubar(k))
            ub = min(ub, level_bound(n, u, self.model))
        return ub

    def enumerated_short(self, n: int, p: float) -> bool:
        """Every n-swarm was scored and none can reach p (upper model)."""
        return n in self.exhausted and self.exhausted_upper.get(n, 0.0) < p - 1e-12

    def out_of_time(self) -> bool:
        """The design's ``time_limit`` has passed."""
        return self.deadline is not None and time.perf_counter() >= self.deadline

    def best_of(self, n: int, target: float = math.inf):
        """Best swarm of n found (exhaustive when the count is within the budget). Once
        :attr:`settled`, the clock no longer cuts it short (every step is bounded): the
        looks' step-ups must not depend on what a first run spent compiling."""
        if n in self.best:
            return self.best[n]
        clock = not self.settled
        n_swarms = math.comb(self.c_n, n)
        if n_swarms <= self.budget and n_swarms * self.s_n <= ENUM_CELLS \
                and not (clock and self.out_of_time()):
            sw = all_swarms(self.c_n, n, self.m)
            if sw.shape[0] == 0:
                self.best[n] = (np.zeros(0, np.int64), 0.0)
            else:
                vals = self.ev(sw)
                i = int(np.argmax(vals))
                self.best[n] = (sw[i], float(vals[i]))
                # the enumeration proves n short only for the upper model's P
                self.exhausted_upper[n] = float(vals[i]) if self.model.in_pass_share == 0 \
                    else float(self.ev.upper(sw).max())
            self.exhausted.add(n)
            return self.best[n]
        starts = []
        if n in self.mip_swarm and not (clock and self.out_of_time()):
            s = self.mip_swarm[n]
            while s is not None and s.size < n:
                s = extend(self.ev, s, self.m)
            if s is not None:
                starts.append(s)
        if n - 1 in self.best and self.best[n - 1][0].size == n - 1:
            s = extend(self.ev, self.best[n - 1][0], self.m) if n > 1 else None
            if s is not None:
                starts.append(s)
        s = np.zeros(0, np.int64)           # greedy from scratch on the exact P
        for _ in range(n):
            s = extend(self.ev, s, self.m) if s is not None else None
        if s is not None:
            starts.append(s)
        top = (np.zeros(0, np.int64), -1.0)
        for s in starts:
            sw, val = improve(self.ev, s, self.m, deadline=self.deadline if clock else None)
            if val > top[1]:
                top = (sw, val)
        sw = top[0] if weights_of(self.model, n).exchangeable else np.sort(top[0])
        top = (sw, max(top[1], 0.0))       # member k: the k-th grid candidate (reliability_eval)
        self.best[n] = top
        return top


def min_swarm_reliable(rows, areas, settings: ReliableSettings | None = None,
                       **keywords) -> ReliableResult:
    """The fewest grid candidates with ``P_bank >= p`` (module docstring).

    Parameters
    ----------
    rows : (S, C, V) bool
        Scenario bank rows.
    areas : (V,) or (S, V) m^2
        Vertex areas, shared or per scenario (each scenario's over its own sum).
    settings : ReliableSettings
        The search (:mod:`ideas_hpc.design.settings`), or the keywords below.
    p : float
        Required success probability, 0 < p < 1.
    p_f : float or FailureModel
        Per-spacecraft failure probability, or the failure model
        (:class:`~ideas_hpc.failures.model.FailureModel`; also ``failures``).
    need : float
        Coverage threshold (area fraction, ``target - eps_tol``).
    n_max : int
    sep_steps : int
        Candidates within this many grid steps conflict.
    time_limit : float, optional
        Seconds for the whole search (programmes get what is left).
    enumerate_budget : int
        Score every swarm of a size when there are at most this many.
    bound_solver : callable, optional
        ``(m, seconds) -> BoundResult`` in place of the programme (tests).
    tolerance_solver : callable, optional
        In place of the per-scenario k-tolerant designs
        (:class:`~ideas_hpc.design.tolerance_bound.ToleranceBound`, tests).
    ring_prebound : bool
        Bound ``U_m`` first by the per-scenario ring-gap bounds (cheap, no programme).

    Raises
    ------
    InputError
        ``p`` when no swarm of at most ``n_max``
        reaches ``p`` on the bank (the message gives the best P found).
    """
    s = settings or ReliableSettings(time_limit_s=keywords.pop("time_limit", None), **keywords)
    d = ReliabilityDesigner(rows, areas, need=s.need, p_f=s.model, sep_steps=s.sep_steps,
                            time_limit=s.time_limit_s, enumerate_budget=s.enumerate_budget,
                            bound_solver=s.bound_solver, tolerance_solver=s.tolerance_solver)
    if s.ring_prebound:
        d.ring_lows(s.n_max)
    res = settle(d, s.p, s.n_max)
    d.settled = True
    return res


def settle(d: ReliabilityDesigner, p: float, n_max: int) -> ReliableResult:
    """The fewest N with ``P_bank >= p`` on designer ``d`` (module docstring; raises
    ``InputError`` on ``p`` as :func:`min_swarm_reliable`)."""
    upper: dict = {}
    unresolved: list = []
    # a sampled bank: the screen before the programme, which can spend the whole time limit
    # on one U_m (issue 42: 100 worlds x 45 candidates; the screen took 16 + 5 s)
    screen_first = d.s_n > 1
    for n in progress.steps(range(1, int(n_max) + 1), "success-probability design",
                            unit="size"):
        upper[n] = d.upper(n, p, refine=not screen_first)
        if upper[n] < p - 1e-12:
            continue
        sw, val = d.best_of(n)
        sc = None
        if val < p - 1e-12 and n not in d.exhausted and not d.out_of_time():
            sc = d.screen(n, p)
            if sc is not None and sc.swarm is not None:
                sw, val = np.sort(sc.swarm), sc.probability
                d.best[n] = (sw, val)
                d.screen_found.add(n)
            elif sc is not None and sc.proven_short:
                upper[n] = min(upper[n], sc.upper)
                d.screen_proved.add(n)
                continue
        if val < p - 1e-12 and screen_first and not d.enumerated_short(n, p):
            upper[n] = min(upper[n], d.upper(n, p))   # the programme, the screen unsettled
            if upper[n] < p - 1e-12:
                continue
        if val >= p - 1e-12:
            bound = unresolved[0] if unresolved else n
            gap = (n - bound) / n
            timed = any(s == "time_limit" for s in d.bound_status.values()) or \
                d.out_of_time()
            status = "optimal" if gap == 0 else ("time_limit" if timed else "feasible")
            notes = []
            if "ring_bound" in d.bound_status.values():
                notes.append(f"the bank ({d.s_n} scenarios x {d.c_n} candidates) is above "
                             "the scenario programme's size: U_m bounded by the per-scenario "
                             "ring-gap bounds only")
            if d.tol_proved:
                notes.append(f"sizes {sorted(d.tol_proved)} proven short of p by the "
                             "per-scenario failure-tolerance bound (fewest spacecraft "
                             "surviving any k failures, ideas_hpc.design.tolerance_bound)")
            if d.screen_proved or d.screen_found:
                notes.append(screen_note(d.screen_proved, d.screen_found))
            if unresolved:
                notes.append(f"sizes {unresolved} are neither proven short of p nor met by a "
                             "swarm found")
            if not weights_of(d.model, n).exchangeable:
                sw = np.sort(sw)
            return ReliableResult(indices=sw, n=n, probability=val,
                                  per_scenario=d.ev.per_scenario([sw])[0], status=status,
                                  bound=float(bound), gap=float(gap),
                                  solve_time=time.perf_counter() - d.t0, upper=upper,
                                  best=dict(d.best), u_bar=dict(d.u_bar), notes=notes,
                                  designer=d)
        if not d.enumerated_short(n, p):
            unresolved.append(n)
    best_p = max((v for _, v in d.best.values()), default=0.0)
    what = ("no swarm" if not unresolved else
            f"no swarm found (sizes {unresolved} unresolved within `time_limit`)")
    raise InputError(f"{p:g} is not reached: {what} of at most {n_max} spacecraft on the "
                     f"{d.s_n} scenarios; the best probability found is {best_p:.4f} (proven "
                     f"upper bound {max(upper.values()):.4f})", field="p")
