"""An uncertain per-spacecraft failure probability: a Beta prior or a list of values (issue 41).

A small satellite's ``p_f`` is known to a factor, not to 2 %. The design's
success probability is then the average over the prior,
``P = E_p[P(X; p)]``. Every quantity the design needs of one swarm size N
(the weight of a survivor set, its count distribution) is a polynomial in
``p`` of degree at most ``2 N + 1`` (each member contributes a factor linear in
``p``, a common-cause event one more per group), so its average is a finite sum
over *nodes*:

* a list of values ``p_1 .. p_G`` (equally likely): the values themselves, weight ``1/G``;
* ``p ~ Beta(a, b)`` with mean ``m`` and standard deviation ``sd``
  (``a + b = m (1 - m) / sd^2 - 1``, ``a = m (a + b)``): the ``G``-point
  Gauss-Jacobi rule for the weight ``p^(a-1) (1 - p)^(b-1)`` on [0, 1], exact for
  every polynomial of degree ``<= 2 G - 1`` (Golub & Welsch, Math. Comp. 23,
  1969; Abramowitz & Stegun 25.4.33). With ``G = d // 2 + 1`` nodes for degree
  ``d`` the average is exact up to rounding, no quadrature noise: e.g. the
  weight of one survivor set of k of N under independent failures is
  ``E[(1 - p)^k p^(N - k)] = B(a + N - k, b + k) / B(a, b)``, which
  ``tests/test_failure_model.py`` checks against ``scipy.special.beta``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import number

#: Quantiles of a Beta prior at which the design reports its fewest N.
BETA_QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)


def probabilities(values, field: str) -> tuple:
    """``values`` checked as probabilities (0..1), errors naming ``field`` (and the item)."""
    out = []
    for i, v in enumerate(values):
        try:
            out.append(number(v, field, lo=0.0, hi=1.0))
        except InputError as e:
            if len(values) == 1:
                raise
            raise InputError(f"item {i} {e.message}", field=field) from None
    return tuple(out)


@dataclass(frozen=True)
class Prior:
    """``p_f`` uncertain: equally likely ``values``, or ``Beta`` with ``mean`` and ``sd``.

    Errors name ``p_f_values`` or ``p_f_sd`` (the campaign maps them to its keys).
    """

    values: tuple = ()
    mean: float = 0.0
    sd: float = 0.0

    def __post_init__(self):
        if self.values:
            object.__setattr__(self, "values", probabilities(self.values, "p_f_values"))
            return
        m = number(self.mean, "p_f", lo=0.0, hi=1.0, lo_open=True, hi_open=True)
        s = number(self.sd, "p_f_sd", lo=0.0, lo_open=True)
        if s * s >= m * (1.0 - m):
            raise InputError(f"{s:g} is too wide for a Beta prior of mean {m:g}: it must be "
                             f"below sqrt(mean (1 - mean)) = {math.sqrt(m * (1 - m)):.4g}",
                             field="p_f_sd")

    @property
    def is_beta(self) -> bool:
        return not self.values

    @property
    def ab(self) -> tuple[float, float]:
        """Beta parameters ``(a, b)`` from the mean and standard deviation."""
        nu = self.mean * (1.0 - self.mean) / (self.sd * self.sd) - 1.0
        return self.mean * nu, (1.0 - self.mean) * nu

    def nodes(self, degree: int) -> tuple[np.ndarray, np.ndarray]:
        """``(p, weight)``: the average of any polynomial of degree ``<= degree`` in p over
        the prior is ``sum weight * f(p)`` (module docstring)."""
        if self.values:
            v = np.asarray(self.values, dtype=np.float64)
            return v, np.full(v.size, 1.0 / v.size)
        from scipy.special import roots_jacobi

        a, b = self.ab
        g = int(degree) // 2 + 1
        x, wt = roots_jacobi(g, b - 1.0, a - 1.0)   # weight (1 - x)^(b-1) (1 + x)^(a-1)
        return np.clip(0.5 * (1.0 + x), 0.0, 1.0), wt / wt.sum()

    def sample(self, rng) -> float:
        """One draw of ``p_f`` from ``rng``."""
        if self.values:
            return float(self.values[int(rng.integers(len(self.values)))])
        return float(rng.beta(*self.ab))

    def levels(self) -> tuple[tuple[float, str], ...]:
        """``((p_f, label), ...)``, increasing: where the design reports its fewest N (the
        distinct values of a list, or the quantiles :data:`BETA_QUANTILES` of a Beta)."""
        if self.values:
            return tuple((v, "value") for v in sorted(set(self.values)))
        from scipy.stats import beta

        a, b = self.ab
        return tuple((float(beta.ppf(q, a, b)), f"{100 * q:g} % quantile")
                     for q in BETA_QUANTILES)

    def describe(self) -> str:
        if self.values:
            return f"p_f equally likely among {', '.join(f'{v:g}' for v in self.values)}"
        a, b = self.ab
        return f"p_f ~ Beta(mean {self.mean:g}, sd {self.sd:g}; a = {a:.4g}, b = {b:.4g})"

    def record(self) -> dict:
        return ({"values": list(self.values)} if self.values else
                {"beta_mean": self.mean, "beta_sd": self.sd})
