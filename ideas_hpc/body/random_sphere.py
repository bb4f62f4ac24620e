"""Gaussian random spheres: the shape family of the target prior (SPEC section 7f).

A Gaussian random sphere (Muinonen et al., JQSRT 55, 577, 1996; Muinonen &
Lagerros, A&A 333, 753, 1998) is the star-shaped surface::

    r(u) = a exp(s(u) - beta^2 / 2),     s(u) = sum_{l=1}^{L} sum_{m=-l}^{l} a_lm Y_lm(u),

with a Gaussian log-radius ``s`` of zero mean and covariance
``beta^2 C_s(gamma)`` between two directions ``gamma`` apart. ``r`` is then
lognormal with mean ``a`` and relative standard deviation ``sigma``:
``beta^2 = ln(1 + sigma^2)``.

Correlation laws
----------------
``C_s(gamma) = sum_l c_l P_l(cos gamma)`` with ``c_l >= 0``, ``sum_l c_l = 1``:

* ``"gaussian"`` (Muinonen 1996 eq. 18): ``C(gamma) = exp(-2 sin^2(gamma/2) / ell^2)``
  with the correlation length ``ell = 2 sin(Gamma / 2)`` of the correlation angle
  ``Gamma`` (Muinonen's definition, ``ell = 1 / sqrt(-C''(0))``; the shorthand
  ``exp(-2 sin^2(gamma/2) / Gamma^2)`` differs by 1.5 % in ``ell`` at 33 deg). Its
  Legendre coefficients are computed here by Gauss-Legendre quadrature,
  ``c_l = (2l + 1) / 2 int_{-1}^{1} C(x) P_l(x) dx`` (``x = cos gamma``); the closed
  form ``(2l + 1) exp(-1/ell^2) i_l(1/ell^2)`` (``i_l`` the modified spherical Bessel
  function) is the tests' oracle.
* ``"power"``: ``c_l = l^-nu / zeta(nu)`` for ``l >= 1``, ``c_0 = 0`` (``nu > 1``).

Fits to real small bodies: ``sigma`` about 0.245 and ``Gamma`` about 33 deg
(Muinonen & Lagerros 1998), the defaults.

Degrees, truncation and variance
--------------------------------
The sum starts at ``l = 1`` (``l = 0`` only rescales the body, which the size
estimate does) and stops at ``L``: by default the smallest degree whose dropped
tail ``sum_{l > L} c_l`` is at most ``variance_lost`` (1e-6) of ``sum_{l >= 1} c_l``
(``1 - c_0`` for the Gaussian law, ``1`` for the power law); a given ``l_max``
overrides it. The kept coefficients are renormalised, so ``Var s(u) = beta^2``
exactly, and the correlation of ``s`` is::

    C_L(gamma) = sum_{l=1}^{L} c_l P_l(cos gamma) / sum_{l=1}^{L} c_l .

With the orthonormal real harmonics used here (``int Y_lm^2 dOmega = 1``, so
``sum_m Y_lm(u) Y_lm(u') = (2l + 1) / (4 pi) P_l(u . u')`` by the addition theorem),
that needs::

    Var(a_lm) = 4 pi beta^2 c_l / ((2l + 1) sum_{k=1}^{L} c_k),

which is SPEC 7f's ``beta^2 c_l / sum c_l`` for harmonics normalised to
``sum_m Y_lm Y_lm = P_l``. Nothing is drawn for ``l > L``;
:attr:`GaussianRandomSphere.variance_kept` is the fraction of ``sum_{l >= 1} c_l``
kept before the renormalisation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import number
from ideas_hpc.base.units import DEG

CORRELATION_LAWS = ("gaussian", "power")
#: Quadrature nodes beyond ``l_max`` for the Gaussian law's Legendre coefficients.
_EXTRA_NODES = 96


@dataclass(frozen=True)
class ShapeFamily:
    """Settings of the Gaussian-random-sphere family (module docstring).

    Attributes
    ----------
    sigma : float
        Relative standard deviation of the radius (0.245, Muinonen & Lagerros 1998);
        0 gives the nominal shape itself.
    law : {"gaussian", "power"}
        Correlation law of the log-radius.
    correlation_angle_rad : float
        ``Gamma`` of the Gaussian law, rad (33 deg).
    nu : float
        Power-law index of ``c_l ~ l^-nu`` (> 1).
    l_max : int or None
        Highest degree; None chooses it from ``variance_lost``.
    variance_lost : float
        Largest fraction of ``sum_{l>=1} c_l`` the automatic ``l_max`` may drop.
    l_max_limit : int
        Highest automatic ``l_max``; a law that needs more is refused (give ``l_max``).
    """

    sigma: float = 0.245
    law: str = "gaussian"
    correlation_angle_rad: float = 33.0 * DEG
    nu: float = 3.0
    l_max: int | None = None
    variance_lost: float = 1e-6
    l_max_limit: int = 40

    def __post_init__(self):
        number(self.sigma, "sigma", lo=0.0)
        if self.law not in CORRELATION_LAWS:
            raise InputError(f"unknown correlation law {self.law!r}; use one of "
                             f"{', '.join(CORRELATION_LAWS)}", field="law")
        number(self.correlation_angle_rad, "correlation_angle_rad", lo=0.0, lo_open=True,
               hi=math.pi)
        number(self.nu, "nu", lo=1.0, lo_open=True)
        number(self.variance_lost, "variance_lost", lo=0.0, lo_open=True, hi=0.5)
        for name in ("l_max", "l_max_limit"):
            v = getattr(self, name)
            if v is None:
                continue
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise InputError(f"must be a whole number >= 1, got {v!r}", field=name)

    @property
    def beta2(self) -> float:
        """Variance of the log-radius, ``beta^2 = ln(1 + sigma^2)``."""
        return math.log1p(self.sigma ** 2)

    @property
    def correlation_length(self) -> float:
        """``ell = 2 sin(Gamma / 2)`` of the Gaussian law (module docstring)."""
        return 2.0 * math.sin(0.5 * self.correlation_angle_rad)


def correlation(family: ShapeFamily, gamma_rad) -> np.ndarray:
    """The law's full correlation ``C(gamma) = sum_{l>=0} c_l P_l(cos gamma)`` (``C(0) = 1``)."""
    g = np.asarray(gamma_rad, dtype=np.float64)
    if family.law == "gaussian":
        return np.exp(-2.0 * np.sin(0.5 * g) ** 2 / family.correlation_length ** 2)
    from scipy.special import eval_legendre, zeta

    l_top = max(family.l_max_limit, 400)
    ls = np.arange(1, l_top + 1, dtype=np.float64)
    w = ls ** -family.nu / float(zeta(family.nu))
    x = np.cos(g)[..., None]
    return (w * eval_legendre(ls.astype(int), x)).sum(axis=-1)


def legendre_coefficients(family: ShapeFamily, l_max: int) -> np.ndarray:
    """The law's Legendre coefficients ``c_l``, ``l = 0`` to ``l_max`` (all ``l``: sum 1).

    Gaussian law: ``c_l = (2l + 1) / 2 int_{-1}^{1} C(x) P_l(x) dx`` by Gauss-Legendre
    quadrature on ``l_max + 96`` nodes (exact for a polynomial of degree ``2 l_max +
    191``; ``C`` is entire, so the error is at round-off), with ``P_l`` by the
    three-term recurrence. Power law: ``c_l = l^-nu / zeta(nu)``.
    """
    l_max = int(l_max)
    if family.law == "power":
        from scipy.special import zeta

        c = np.zeros(l_max + 1)
        ls = np.arange(1, l_max + 1, dtype=np.float64)
        c[1:] = ls ** -family.nu / float(zeta(family.nu))
        return c
    x, w = np.polynomial.legendre.leggauss(l_max + _EXTRA_NODES)
    cx = np.exp(-(1.0 - x) / family.correlation_length ** 2)
    c = np.empty(l_max + 1)
    p_prev, p = np.zeros_like(x), np.ones_like(x)
    for l in range(l_max + 1):
        c[l] = 0.5 * (2 * l + 1) * float(np.dot(w, cx * p))
        # Bonnet: (l + 1) P_{l+1} = (2l + 1) x P_l - l P_{l-1}
        p_prev, p = p, ((2 * l + 1) * x * p - l * p_prev) / (l + 1)
    return np.clip(c, 0.0, None)   # round-off below 1e-17 must not make a negative variance


def _tail_total(family: ShapeFamily, c: np.ndarray) -> float:
    """``sum_{l >= 1} c_l`` over all degrees: ``1 - c_0`` (both laws have ``sum c_l = 1``)."""
    return 1.0 - float(c[0])


def choose_l_max(family: ShapeFamily) -> int:
    """The truncation degree ``L`` (module docstring): ``family.l_max`` when given, else the
    smallest ``L >= 2`` whose dropped tail is at most ``variance_lost`` of ``sum_{l>=1} c_l``."""
    if family.l_max is not None:
        return int(family.l_max)
    top = int(family.l_max_limit)
    c = legendre_coefficients(family, top)
    total = _tail_total(family, c)
    kept = np.cumsum(c[1:]) / total          # kept[L - 1]: fraction kept up to degree L
    ok = np.nonzero(1.0 - kept <= family.variance_lost)[0]
    if ok.size == 0:
        raise InputError(f"the {family.law} law keeps only {100 * kept[-1]:.4g} % of the "
                         f"log-radius variance at degree {top}; give `l_max` or raise "
                         "`variance_lost`", field="l_max")
    return max(2, int(ok[0]) + 1)


def degree_variances(family: ShapeFamily, l_max: int) -> np.ndarray:
    """``Var(a_lm)`` for each degree ``l`` from 0 to ``L`` (0 at ``l = 0``), orthonormal harmonics:
    ``4 pi beta^2 c_l / ((2l + 1) sum_{k=1}^{L} c_k)`` (module docstring)."""
    c = legendre_coefficients(family, l_max)
    c[0] = 0.0
    ls = np.arange(l_max + 1)
    return 4.0 * math.pi * family.beta2 * c / ((2 * ls + 1) * c.sum())


def real_harmonics(directions, l_max: int) -> np.ndarray:
    """Orthonormal real spherical harmonics at unit ``directions`` ``(V, 3)``: ``(V, (L+1)^2)``.

    Column ``l^2 + l + m`` holds ``Y_lm``: ``N_l0 P_l`` for ``m = 0``,
    ``sqrt(2) N_lm P_l^m(cos theta) cos(m phi)`` for ``m > 0`` and
    ``sqrt(2) N_l|m| P_l^|m| sin(|m| phi)`` for ``m < 0`` (no Condon-Shortley phase),
    ``int Y_lm^2 dOmega = 1``. The fully normalised ``P_l^m`` come from the standard
    stable recurrences (e.g. Holmes & Featherstone, J. Geodesy 76, 2002, eqs. 11-13),
    ``theta`` the colatitude from +z and ``phi`` the longitude from +x.
    """
    u = np.asarray(directions, dtype=np.float64)
    L = int(l_max)
    ct = np.clip(u[:, 2], -1.0, 1.0)
    st = np.sqrt(np.maximum(0.0, 1.0 - ct * ct))
    phi = np.arctan2(u[:, 1], u[:, 0])
    out = np.empty((u.shape[0], (L + 1) ** 2))
    pmm = np.full_like(ct, 1.0 / math.sqrt(4.0 * math.pi))
    for m in range(L + 1):
        if m > 0:
            pmm = math.sqrt((2 * m + 1) / (2.0 * m)) * st * pmm
        cm, sm = np.cos(m * phi), np.sin(m * phi)
        p_prev, p = np.zeros_like(ct), pmm
        for l in range(m, L + 1):
            if l == m + 1:
                p_prev, p = p, math.sqrt(2 * m + 3) * ct * pmm
            elif l > m + 1:
                a = math.sqrt((4.0 * l * l - 1.0) / (l * l - m * m))
                b = math.sqrt(((l - 1.0) ** 2 - m * m) / (4.0 * (l - 1.0) ** 2 - 1.0))
                p_prev, p = p, a * (ct * p - b * p_prev)
            base = l * l + l
            if m == 0:
                out[:, base] = p
            else:
                out[:, base + m] = math.sqrt(2.0) * p * cm
                out[:, base - m] = math.sqrt(2.0) * p * sm
    return out


class GaussianRandomSphere:
    """The family's log-radius field at fixed unit ``directions`` ``(V, 3)``.

    The harmonics matrix is built once; each draw is one ``standard_normal`` call
    of ``(L+1)^2 - 1`` numbers (degree by degree, ``m`` from ``-l`` to ``l``) and one product,
    so the same generator state gives the same field bit for bit.
    """

    def __init__(self, family: ShapeFamily, directions):
        self.family = family
        self.l_max = choose_l_max(family)
        top = max(self.l_max, family.l_max_limit)
        c = legendre_coefficients(family, top)
        #: Fraction of ``sum_{l>=1} c_l`` within ``l <= L`` (before renormalisation).
        self.variance_kept = float(c[1:self.l_max + 1].sum() / _tail_total(family, c))
        var = degree_variances(family, self.l_max)
        ls = np.repeat(np.arange(self.l_max + 1), 2 * np.arange(self.l_max + 1) + 1)
        self._sd = np.sqrt(var[ls])[1:]
        self._y = np.ascontiguousarray(real_harmonics(directions, self.l_max)[:, 1:])

    @property
    def n_coefficients(self) -> int:
        return int(self._sd.size)

    def log_radius(self, rng: np.random.Generator) -> np.ndarray:
        """One draw of ``s`` at the directions, ``(V,)``: zero mean, variance ``beta^2``."""
        a = rng.standard_normal(self._sd.size) * self._sd
        return self._y @ a

    def radius_factor(self, rng: np.random.Generator) -> np.ndarray:
        """``exp(s - beta^2 / 2)`` at the directions: lognormal, mean 1, relative sd ``sigma``."""
        return np.exp(self.log_radius(rng) - 0.5 * self.family.beta2)


def radial_graph_problem(vertices, faces, centre=(0.0, 0.0, 0.0)) -> str | None:
    """Why the mesh is not a radial graph about ``centre`` (every ray from it meets the
    surface once), or None.

    A flat triangle projects from ``centre`` onto the geodesic triangle of its
    vertices' directions whatever their distances, so the central projection is a
    map of the closed mesh onto the sphere; when every face's oriented solid angle
    (Van Oosterom & Strackee, IEEE Trans. Biomed. Eng. 30, 1983) is positive and they
    sum to ``4 pi``, it is a degree-one covering with no fold, i.e. one-to-one: the mesh
    is star-shaped about ``centre``, outward wound and free of self-intersection. Moving
    vertices along their rays by any positive factor keeps all of this, which is why
    every draw of the family is a valid mesh.
    """
    v = np.asarray(vertices, dtype=np.float64) - np.asarray(centre, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    if np.any(np.minimum(np.minimum(la, lb), lc) == 0.0):
        return "a vertex lies on the centre"
    num = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc
           + np.einsum("ij,ij->i", a, c) * lb + np.einsum("ij,ij->i", b, c) * la)
    omega = 2.0 * np.arctan2(num, den)
    bad = int(np.sum(omega <= 0.0))
    if bad:
        return (f"{bad} faces are seen edge-on or from behind from the centre (the mesh is not "
                "star-shaped about it)")
    total = float(omega.sum())
    if abs(total - 4.0 * math.pi) > 1e-9 * 4.0 * math.pi:
        return (f"the faces' solid angles sum to {total / math.pi:.9g} pi, not 4 pi (the "
                "projection folds or leaves a gap)")
    return None
