"""The design methods: one vocabulary from the campaign file to the store (issue 40).

``design.method`` takes a name of :data:`METHODS`; the store's ``design_method`` holds
the same name (the method of the registered designer that produced the result,
:func:`method_of_designer`), and the report and the checks read the method's
capabilities, never its name, so a new method is one :class:`Method` entry here (plus
its designers in :mod:`ideas_hpc.design.api.designers` and its run function in the kinds
registry when it needs one). ``tests/test_recipe_methods.py`` refuses a method name
compared anywhere else.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Method:
    """A design method.

    ``designers``: the registered designers (:data:`ideas_hpc.design.api.result.DESIGNERS`)
    that run under it. Capabilities:

    ``proven``
        Its results carry a proven bound and gap (integer programmes and proofs); the
        report states the requirement and the solver's notes with them.
    ``continuous_angles``
        It may search continuous ring angles (``design.angle_step_deg = 0``); a grid is
        still needed where pairs are scored on it (stereo).
    ``success_probability``
        It designs for ``design.success_probability`` (the scenario bank).
    ``aliases``
        Former stored spellings read as this method (stores written before issue 40).
    """

    name: str
    doc: str
    designers: tuple[str, ...]
    proven: bool
    continuous_angles: bool = False
    success_probability: bool = False
    aliases: tuple[str, ...] = ()


METHODS: dict[str, Method] = {m.name: m for m in (
    Method("exact", "integer programmes and proofs on the candidate grid (HiGHS)",
           ("exact", "failure-tolerant", "stereo", "success-probability"), proven=True,
           success_probability=True, aliases=("exact-reliability",)),
    Method("ga", "the paper's genetic algorithm (pygad), with its gap to the exact optimum "
           "when that is known", ("ga-nadir", "ga-fov"), proven=False, continuous_angles=True),
)}


def method_of(name) -> Method:
    """The method of a ``design.method`` value or a stored ``design_method`` (aliases read)."""
    key = str(name)
    for m in METHODS.values():
        if key == m.name or key in m.aliases:
            return m
    raise ValueError(f"unknown design method {key!r}; one of {', '.join(METHODS)}")


def method_of_designer(designer: str) -> Method:
    """The method a registered designer runs under (:attr:`Method.designers`)."""
    for m in METHODS.values():
        if designer in m.designers:
            return m
    raise ValueError(f"designer {designer!r} belongs to no method of {', '.join(METHODS)}")
