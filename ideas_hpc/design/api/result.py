"""The result type, the designer registry and :func:`minimize`."""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Any, Callable

import numpy as np


@dataclass(frozen=True, eq=False)
class DesignResult:
    """What every designer returns.

    Attributes
    ----------
    designer : str
        The registry name of the designer that ran.
    swarm_rad : (N,) float
        The chosen swarm's angles, rad (the FoV design: the given swarm's).
    indices : (N,) int
        The chosen candidates' indices in the problem's bank (empty when the
        designer searches continuous angles or sweep periods).
    n : int
        Swarm size.
    status : str
        ``"optimal"``, ``"time_limit"``, ... for the proven designers; ``"ga"`` or
        ``"front"`` for the searches that prove nothing.
    bound : float
        Proven lower bound on N (NaN when nothing is proven).
    gap : float
        Relative gap ``(N - bound) / N`` (NaN when nothing is proven).
    value : float
        The design's score: coverage (fraction) or success probability.
    notes : tuple of str
    timings_s : dict
        ``{"solve": s, "wall": s}``: the designer's own solve time and the wall
        time of :func:`minimize`.
    detail : object
        The designer's own record (``ExactResult``, ``ReliableResult``,
        ``GAResult``, ``ParetoResult``) for the store variables only it has.
    """

    designer: str
    swarm_rad: np.ndarray
    indices: np.ndarray
    n: int
    status: str
    bound: float
    gap: float
    value: float
    notes: tuple = ()
    timings_s: dict = field(default_factory=dict)
    detail: Any = field(default=None, repr=False)

    @property
    def optimal(self) -> bool:
        return self.status == "optimal"


@dataclass(frozen=True)
class Designer:
    """A registered designer.

    ``settings``: the frozen settings class it reads; ``problem``: the problem
    class it searches (None: any); ``applies(settings)``: when it, of the
    designers sharing those two, is the one; ``solve(problem, settings,
    progress)`` returns a :class:`DesignResult` (its ``timings_s["wall"]`` is
    filled in by :func:`minimize`).
    """

    name: str
    settings: type
    problem: type | tuple | None
    solve: Callable
    applies: Callable = field(default=lambda s: True)
    doc: str = ""

    def takes(self, problem, settings) -> bool:
        return (isinstance(settings, self.settings)
                and (self.problem is None or isinstance(problem, self.problem))
                and bool(self.applies(settings)))


#: Every designer, by name (:func:`register` adds one).
DESIGNERS: dict[str, Designer] = {}


def register(designer: Designer) -> Designer:
    """Add ``designer`` to :data:`DESIGNERS` (a name registered twice is an error)."""
    if designer.name in DESIGNERS:
        raise ValueError(f"designer {designer.name!r} is registered twice")
    DESIGNERS[designer.name] = designer
    return designer


def designer_for(problem, settings) -> Designer:
    """The one registered designer that takes ``problem`` with ``settings``."""
    hits = [d for d in DESIGNERS.values() if d.takes(problem, settings)]
    if len(hits) != 1:
        what = "no designer" if not hits else "designers " + ", ".join(d.name for d in hits)
        raise ValueError(f"{what} for a {type(problem).__name__} with "
                         f"{type(settings).__name__}; registered: {', '.join(DESIGNERS)}")
    return hits[0]


def minimize(problem, settings, *, progress=None) -> DesignResult:
    """Run the designer that ``settings`` and ``problem`` select; ``progress`` is the
    search's per-generation callback where it has one."""
    d = designer_for(problem, settings)
    t0 = time.perf_counter()
    res = d.solve(problem, settings, progress)
    return replace(res, timings_s={**res.timings_s, "wall": time.perf_counter() - t0})

