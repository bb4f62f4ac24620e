"""Drawn failures: one home for the sampling of a failure model (issue 41).

:func:`draw_failures` draws one sample's losses of a swarm of n. The uniforms ``u``
that decide the independent failures (member k lost when ``u_k < (1 - beta) Q_k``)
and, for exactly-k losses, the permutation whose first k are lost, come from the
caller, so each caller keeps the numbers it has always drawn: the Monte Carlo kind
its ``permutation(n)`` then ``uniform(n)`` on the dispersions' shared stream
(:mod:`ideas_hpc.montecarlo.dispersions`), the validation its ``random(n)``
(:func:`validation_failures`). Everything the model adds is drawn from ``rng``,
in this order and only when the model has it: the prior's ``p_f``, the permutation
(when not given), one uniform per common-cause group, then per member an in-pass
flag (``random(n) < in_pass_share``) and a loss time (``random(n)``, a fraction of
the pass). With today's model nothing is drawn from ``rng`` and the losses are
today's, bit for bit.

The validation (:func:`validation_failures`, :func:`sample_probabilities`,
:func:`drawn_coverage`) scores the flights of a swarm through fresh samples; sample
m's failure draws come from ``(VALIDATION_STREAM, m, STREAM_FAILURES)``
(:mod:`ideas_hpc.base.seeds`): first ``u``, then the model's own draws.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ideas_hpc.base.vertex_weights import row
from ideas_hpc.base.seeds import STREAM_FAILURES, VALIDATION_STREAM, stream_rng
from ideas_hpc.core.design.reliability import weighted_probabilities
from ideas_hpc.failures.model import FailureModel
from ideas_hpc.failures.weights import kernel_weights


@dataclass(frozen=True)
class FailureDraw:
    """One sample's losses of a swarm of n: ``failed`` (n,) bool, ``in_pass`` (n,) bool
    (a loss of that member would happen during the pass) and ``loss_fraction`` (n,) (its
    time, a fraction of the pass from its start; read where ``in_pass``)."""

    failed: np.ndarray
    in_pass: np.ndarray
    loss_fraction: np.ndarray

    @property
    def active(self) -> np.ndarray:
        """(n,) bool: working for the whole pass."""
        return ~self.failed


def draw_failures(model: FailureModel, n: int, u, rng, perm=None) -> FailureDraw:
    """One sample's losses (module docstring): ``u`` (n,) uniforms, ``rng`` the model's own
    draws, ``perm`` the exactly-k permutation when the caller draws it."""
    u = np.asarray(u, dtype=np.float64)
    p = model.prior.sample(rng) if model.prior is not None else None
    q = np.asarray(model.member_q(n, p), dtype=np.float64)
    failed = u < (1.0 - model.beta) * q if model.beta else u < q
    if model.failures_k:
        if perm is None:
            perm = rng.permutation(n)
        failed[np.asarray(perm)[:model.failures_k]] = True
    if model.beta:
        for g in model.cc_groups(n):
            if rng.random() < model.beta * max(q[j] for j in g):
                failed[list(g)] = True
    if model.in_pass_share:
        in_pass = rng.random(n) < model.in_pass_share
        frac = rng.random(n)
    else:
        in_pass, frac = np.zeros(n, dtype=bool), np.full(n, np.inf)
    return FailureDraw(failed=failed, in_pass=in_pass, loss_fraction=frac)


def validation_failures(model: FailureModel, n: int, seed: int, first: int,
                        m: int, stream: int = VALIDATION_STREAM) -> list[FailureDraw]:
    """The losses of validation samples ``first`` to ``first + m - 1`` (module docstring);
    ``stream`` another design stream's samples (the held-out scenarios')."""
    out = []
    for k in range(int(m)):
        rng = stream_rng(seed, int(stream), int(first) + k, STREAM_FAILURES)
        out.append(draw_failures(model, n, rng.random(n), rng))
    return out


def seen_early(draw: FailureDraw, seen_fraction) -> np.ndarray | None:
    """(n, V) bool: what each member lost in the pass imaged before its loss (``seen_fraction``
    (n, V): the pass fraction of each member's first image of each vertex, ``inf`` never);
    None when no member has an in-pass loss or no times are known (whole-pass scoring)."""
    if seen_fraction is None or not draw.in_pass.any():
        return None
    return draw.in_pass[:, None] & (seen_fraction < draw.loss_fraction[:, None])


def sample_probabilities(rows, w, need: float, model: FailureModel, draws,
                         seen_fraction=None) -> np.ndarray:
    """(M,) exact failure-weighted P of each validation flight of one swarm.

    ``rows`` (M, N, V) bool. Which members fail is enumerated exactly (weights of
    :func:`~ideas_hpc.failures.weights.kernel_weights`). A loss in the pass, with the
    first-seen times ``seen_fraction`` (M, N, V), is drawn per member and sample
    (``draws``): a vertex a member sees before its drawn loss time is covered whatever
    fails (that member either survives, or images it before its loss), so it is taken
    out of the enumeration (weight 0, threshold lowered by its area) and the zeta
    transform of the exact kernel stays. Without times the loss counts as whole-pass
    (a lower bound on P). ``w``: vertex fractions, (V,) shared or (M, V) per sample (each
    sample a drawn world, issue 42).
    """
    rows = np.ascontiguousarray(rows, dtype=np.bool_)
    w = np.ascontiguousarray(w, dtype=np.float64)
    m_n, n = rows.shape[0], rows.shape[1]
    weights = kernel_weights(model, n)
    swarm = np.arange(n, dtype=np.int64)[None, :]
    early = [None if seen_fraction is None else seen_early(d, seen_fraction[k])
             for k, d in enumerate(draws)] if draws is not None else [None] * m_n
    if all(e is None for e in early):
        return weighted_probabilities(rows, swarm, w, need, weights)[0]
    out = np.empty(m_n)
    for k in range(m_n):
        if early[k] is None:
            out[k] = weighted_probabilities(rows[k:k + 1], swarm, row(w, k), need,
                                            weights)[0, 0]
            continue
        sure = early[k].any(axis=0)
        wk = row(w, k)
        w_k = np.where(sure, 0.0, wk)
        out[k] = weighted_probabilities(rows[k:k + 1], swarm, w_k, need - float(wk[sure].sum()),
                                        weights)[0, 0]
    return out


def drawn_coverage(rows, w, draws, seen_fraction=None) -> tuple[np.ndarray, np.ndarray]:
    """``(coverage (M,), lost (M,) int32)`` of each flight with its losses drawn: the
    survivors' union plus what members lost in the pass imaged before their loss; ``w``
    (V,) shared or (M, V) per sample."""
    m_n = rows.shape[0]
    cov = np.empty(m_n)
    lost = np.empty(m_n, dtype=np.int32)
    for k, d in enumerate(draws):
        alive = d.active
        seen = rows[k, alive].any(axis=0) if alive.any() else np.zeros(rows.shape[2], bool)
        early = None if seen_fraction is None else seen_early(d, seen_fraction[k])
        if early is not None:
            seen = seen | (early & d.failed[:, None]).any(axis=0)
        cov[k] = float(row(w, k)[seen].sum()) if seen.any() else 0.0
        lost[k] = int(d.failed.sum())
    return cov, lost
