"""One vocabulary of design methods from the campaign file to the store (issue 40): the
file's ``design.method``, the registered designers and the stored ``design_method`` all
name a :data:`~ideas_hpc.design.api.methods.METHODS` entry, and no method name is compared
outside that registry."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from ideas_hpc.design.api.methods import METHODS, method_of, method_of_designer
from ideas_hpc.design.api.result import DESIGNERS

PACKAGE = Path(__file__).resolve().parents[1] / "ideas_hpc"


def test_every_registered_designer_runs_under_one_method_at_most():
    """At most one: a designer of a kind without ``design.method`` (NSGA-II's Pareto
    front, which stores no ``design_method``) belongs to none."""
    for name in DESIGNERS:
        owners = [m.name for m in METHODS.values() if name in m.designers]
        assert len(owners) <= 1, f"designer {name!r} belongs to {owners}"
        if owners:
            assert method_of_designer(name).name == owners[0]
    for m in METHODS.values():
        assert set(m.designers) <= set(DESIGNERS), f"{m.name}: unknown designers"


def test_stored_spellings_of_older_stores_read_as_their_method():
    assert method_of("exact-reliability") is METHODS["exact"]
    with pytest.raises(ValueError, match="unknown design method"):
        method_of("simulated-annealing")


def _reads_method(node) -> bool:
    return any(isinstance(n, ast.Attribute) and n.attr in ("method", "design_method")
               or isinstance(n, ast.Name) and n.id in ("method", "design_method")
               or isinstance(n, ast.Constant) and n.value == "design_method"
               for n in ast.walk(node))


def test_no_method_name_is_compared_outside_the_registry():
    """A comparison that reads a method (``d.method``, ``design_method``) against a literal
    is refused outside ``design/api/methods.py`` and the kinds registry: code reads the
    method's capabilities (``proven``, ``continuous_angles``, ``success_probability``)."""
    names = {n for m in METHODS.values() for n in (m.name, *m.aliases)}
    hits = []
    for f in PACKAGE.rglob("*.py"):
        if f.name in ("methods.py", "kinds.py"):
            continue
        for node in ast.walk(ast.parse(f.read_text(), str(f))):
            if isinstance(node, ast.Compare) and _reads_method(node):
                hits += [f"{f.relative_to(PACKAGE)}:{node.lineno}" for c in ast.walk(node)
                         if isinstance(c, ast.Constant) and c.value in names]
    assert not hits, f"design method names compared outside the registry: {hits}"


def test_the_checker_sees_a_comparison(tmp_path, monkeypatch):
    """The walk above fails on ``d.method == "ga"`` (the check can fail)."""
    tree = ast.parse('if d.method == "ga":\n    pass\n')
    cmp = next(n for n in ast.walk(tree) if isinstance(n, ast.Compare))
    assert _reads_method(cmp)
