"""The failure model of a swarm: who is lost, how, and when (issue 41, docs/failure-model.md).

One record, :class:`FailureModel`, says it for the designer, its bounds, the validation
and the Monte Carlo kind alike. For a swarm of N members (member k is flown by
spacecraft k of the fleet: in a design, the k-th of its grid candidates in increasing
grid order, the stored order; in a file's swarm, the k-th angle):

* **Independent failures.** Member k is lost with probability ``(1 - beta) Q_k``,
  independently of the others; ``Q_k = p_f[k]`` (a list, one value per fleet
  spacecraft) or the one ``p_f`` of every member.
* **Common-cause failures (beta factor,** IEC 61508-6 annex D; NUREG/CR-5485,
  Mosleh et al. 1998, sec. 5.2). A common-cause event of probability
  ``beta Q_g`` takes out every member of its group g at once, independently of the
  independent failures and of the other groups' events. The groups are the whole
  swarm (default) or the stated ones; a member in no stated group is a group of
  its own (its common-cause share still fails it, alone), so ``beta`` never changes
  what a lone member risks. ``Q_g`` is the largest ``Q_k`` of the group, the
  conservative choice when members differ (a larger common-cause probability only
  lowers P). Each member's total loss probability is
  ``1 - (1 - (1 - beta) Q_k)(1 - beta Q_g) = Q_k - beta (1 - beta) Q_k Q_g`` for
  ``Q_k = Q_g``: the beta-factor split of Q (the rare-event sum
  ``(1 - beta) Q + beta Q`` without the double count).
* **Exactly k lost** (``failures_k``, as the Monte Carlo kind has always drawn it:
  a uniformly random k-subset lost, and the independent failures on top).
* **Uncertain p_f** (:class:`~ideas_hpc.failures.prior.Prior`: Beta or equally
  likely values): every member shares the one drawn ``p``; the design averages over
  it exactly.
* **Loss in the pass.** A share ``in_pass_share`` of losses (independently per
  member and loss) happens during the pass, at a time uniform over it; the member
  images until then. The others happen before the pass (whole-pass losses).

The survivor set T of a swarm then has a law ``pi(T)`` (:mod:`ideas_hpc.failures.weights`);
the model is *exchangeable* at size N when ``pi(T)`` depends on ``|T|`` only (one p_f for
the members, and ``beta = 0`` or one group of all of them).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import number
from ideas_hpc.failures.prior import Prior, probabilities


@dataclass(frozen=True)
class FailureModel:
    """The failure model of the module docstring.

    Parameters
    ----------
    p_f : tuple of float
        Per fleet spacecraft (one value: every member), 0..1.
    beta : float
        Common-cause share, 0..1.
    groups : tuple of tuple of int, optional
        Common-cause groups of fleet spacecraft (0-based, disjoint); None: the whole swarm.
    in_pass_share : float
        Share of losses during the pass, 0..1.
    prior : Prior, optional
        Uncertain p_f (then ``p_f`` holds one value, unused).
    failures_k : int
        Exactly this many members lost, uniformly at random, besides the independent failures.

    Errors name these parameters (``p_f``, ``beta``, ``groups``, ``in_pass_share``,
    ``failures_k``, ``p_f_sd``, ``p_f_values``); the campaign maps them to its keys.
    """

    p_f: tuple = (0.0,)
    beta: float = 0.0
    groups: tuple | None = None
    in_pass_share: float = 0.0
    prior: Prior | None = None
    failures_k: int = 0

    def __post_init__(self):
        p = self.p_f if isinstance(self.p_f, (tuple, list, np.ndarray)) else (self.p_f,)
        if len(p) == 0:
            raise InputError("needs at least one value", field="p_f")
        vals = probabilities(p, "p_f")
        object.__setattr__(self, "p_f", vals)
        number(self.beta, "beta", lo=0.0, hi=1.0)
        number(self.in_pass_share, "in_pass_share", lo=0.0, hi=1.0)
        k = self.failures_k
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 0:
            raise InputError(f"must be a whole number >= 0, got {k!r}", field="failures_k")
        object.__setattr__(self, "failures_k", int(k))
        if self.groups is not None:
            object.__setattr__(self, "groups", _check_groups(self.groups))
        if self.prior is not None and len(vals) > 1:
            raise InputError("an uncertain p_f (`p_f_sd` or `p_f_values`) is one p_f shared "
                             "by every spacecraft: give `p_f` one value", field="p_f")
        if self.failures_k and not self.exchangeable_everywhere:
            raise InputError("with per-spacecraft `p_f` or common-cause `groups` is not "
                             "supported: exactly-k losses need one p_f and one group",
                             field="failures_k")

    # ------------------------------------------------------------------ structure
    @classmethod
    def fixed(cls, p_f: float) -> "FailureModel":
        """Today's model: independent, one ``p_f`` for every spacecraft, whole-pass losses."""
        return cls(p_f=(float(p_f),))

    @property
    def is_plain(self) -> bool:
        """Independent failures of one known p_f, whole-pass: the model before issue 41
        (its weights are computed exactly as then, bit for bit)."""
        return (len(self.p_f) == 1 and self.beta == 0.0 and self.prior is None
                and self.failures_k == 0 and self.in_pass_share == 0.0)

    @property
    def exchangeable_everywhere(self) -> bool:
        """Exchangeable at every swarm size (one p_f; no common cause or one group of all)."""
        return len(set(self.p_f)) == 1 and (self.beta == 0.0 or self.groups is None)

    def exchangeable(self, n: int) -> bool:
        """``pi(T)`` depends on ``|T|`` only for swarms of ``n`` (module docstring)."""
        if len(set(self.member_q(n))) > 1:
            return False
        return self.beta == 0.0 or len(self.cc_groups(n)) <= 1

    def fleet(self) -> int | None:
        """Spacecraft the model names (per-spacecraft p_f, or the groups' largest index + 1);
        None when it names none."""
        sizes = [len(self.p_f)] if len(self.p_f) > 1 else []
        if self.groups:
            sizes.append(max(max(g) for g in self.groups) + 1)
        return max(sizes) if sizes else None

    def check_size(self, n: int) -> None:
        """Refuse swarms of more than the listed spacecraft (field ``p_f``)."""
        if len(self.p_f) > 1 and n > len(self.p_f):
            raise InputError(f"has {len(self.p_f)} values (one per spacecraft) for a swarm of "
                             f"up to {n}: give one per spacecraft that may fly", field="p_f")

    def member_q(self, n: int, p: float | None = None) -> tuple:
        """``Q_k`` of members 0 to n - 1 (``p``: the prior's drawn value)."""
        if p is not None or len(self.p_f) == 1:
            return (float(self.p_f[0] if p is None else p),) * int(n)
        self.check_size(n)
        return self.p_f[:int(n)]

    def cc_groups(self, n: int) -> list:
        """The common-cause groups of a swarm of n (module docstring): the stated groups cut
        to members ``< n``, every other member alone; None stated: one group of all."""
        if self.groups is None:
            return [tuple(range(int(n)))] if n else []
        out = [tuple(i for i in g if i < n) for g in self.groups]
        out = [g for g in out if g]
        named = {i for g in out for i in g}
        return out + [(i,) for i in range(int(n)) if i not in named]

    def at(self, p_f: float) -> "FailureModel":
        """This model with ``p_f`` known to be ``p_f`` (the design's N at the prior's levels)."""
        return replace(self, p_f=(float(p_f),), prior=None)

    def p_nodes(self, degree: int) -> tuple[np.ndarray | None, np.ndarray]:
        """``(p, weight)`` nodes averaging a polynomial of degree ``<= degree`` in p over the
        prior exactly; ``(None, [1])`` without a prior (``member_q`` then reads ``p_f``)."""
        if self.prior is None:
            return None, np.ones(1)
        return self.prior.nodes(degree)

    # ------------------------------------------------------------------ words
    def describe(self) -> str:
        """One line: which model (stores and reports say it)."""
        parts = []
        if self.prior is not None:
            parts.append(self.prior.describe())
        elif len(self.p_f) > 1:
            parts.append("p_f per spacecraft " + ", ".join(f"{v:g}" for v in self.p_f))
        else:
            parts.append(f"p_f = {self.p_f[0]:g} each")
        parts.append("independent" if self.beta == 0.0 else
                     f"common cause beta = {self.beta:g} over "
                     + ("the whole swarm" if self.groups is None else
                        "groups " + " ".join("{" + ",".join(map(str, g)) + "}"
                                             for g in self.groups)))
        if self.failures_k:
            parts.append(f"exactly {self.failures_k} lost besides")
        parts.append("whole-pass losses" if self.in_pass_share == 0.0 else
                     f"{100 * self.in_pass_share:g} % of losses in the pass (uniform time)")
        return "; ".join(parts)

    def record(self) -> dict:
        """The resolved model as plain values (a store attr)."""
        out = {"p_f": list(self.p_f), "common_cause_beta": self.beta,
               "common_cause_groups": None if self.groups is None else
               [list(g) for g in self.groups],
               "in_pass_share": self.in_pass_share, "failures_k": self.failures_k}
        if self.prior is not None:
            out["prior"] = self.prior.record()
        return out


def as_model(x) -> FailureModel:
    """A :class:`FailureModel` from a model or a bare ``p_f`` (the designers' older keyword)."""
    return x if isinstance(x, FailureModel) else FailureModel.fixed(float(x))


def _check_groups(groups) -> tuple:
    if not isinstance(groups, (list, tuple)):
        raise InputError(f"must be a list of lists of spacecraft indices, got {groups!r}",
                         field="groups")
    out, seen = [], set()
    for i, g in enumerate(groups):
        if not isinstance(g, (list, tuple)) or not g:
            raise InputError(f"group {i} must be a non-empty list of spacecraft indices, got "
                             f"{g!r}", field="groups")
        for j in g:
            if isinstance(j, bool) or not isinstance(j, (int, np.integer)) or j < 0:
                raise InputError(f"group {i}: spacecraft indices are whole numbers >= 0 "
                                 f"(0: the first), got {j!r}", field="groups")
            if int(j) in seen:
                raise InputError(f"spacecraft {int(j)} is in two groups (groups are disjoint)",
                                 field="groups")
            seen.add(int(j))
        out.append(tuple(sorted(int(j) for j in g)))
    return tuple(out)
