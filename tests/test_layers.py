"""The layer order of CONTRIBUTING.md, enforced with plain ``ast`` over ``ideas_hpc``.

Data flows one way: cli -> report and export (they read stores, and re-fly them
through the campaign layer) -> campaign (kinds and schema) -> flyby / design /
montecarlo -> models (body, dynamics, attitude, mapping, plots) -> the
execution engine and the ``core/`` kernels -> the ground floor ``base/`` (errors,
units, constants, seeds, progress, fields, instrument, spice). A module may import its own
layer or any layer below it; folders of one layer may import each other, but
never in a cycle. Every import counts, also those inside functions: a lazy
import still ties the folders together.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "ideas_hpc"

#: Bottom to top. A folder is named by its path under ``ideas_hpc`` ("" for
#: the package's own modules); a module listed by file overrides its folder.
LAYERS = (
    ("ground", ("base", "_version.py")),
    ("kernels and engine", ("core", "core/attitude", "core/design", "core/dynamics",
                            "core/mapping", "engine")),
    ("models", ("body", "dynamics", "attitude", "mapping", "plots", "failures")),
    ("flyby, design, montecarlo", ("flyby", "design", "design/api", "design/ga", "design/pareto",
                                   "montecarlo")),
    ("campaign", ("campaign", "campaign/schema")),
    ("report and export", ("report", "export")),
    ("cli", ("cli.py", "commands.py", "__init__.py")),
)


def _rank_table():
    return {unit: rank for rank, (_, units) in enumerate(LAYERS) for unit in units}


def _modules():
    """Dotted module name -> file, for every module of the package."""
    out = {}
    for f in PACKAGE.rglob("*.py"):
        parts = f.relative_to(PACKAGE.parent).with_suffix("").parts
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = f
    return out


def _unit(f: Path) -> str:
    """The layer unit of a file: its own name if the table lists it, else its folder."""
    rel = f.relative_to(PACKAGE)
    if rel.as_posix() in _rank_table():
        return rel.as_posix()
    return rel.parent.as_posix() if rel.parent.as_posix() != "." else ""


def _imported(f: Path, node, modules) -> list[str]:
    """The dotted names an import statement loads: ``from p import m`` loads the
    module ``p.m`` when there is one, else ``p`` (``m`` is an attribute)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    pkg = list(f.relative_to(PACKAGE.parent).with_suffix("").parts[:-1])
    if node.level:
        base = pkg[:len(pkg) - (node.level - 1)]
        mod = ".".join(base + ([node.module] if node.module else []))
    else:
        mod = node.module or ""
    return [f"{mod}.{a.name}" if f"{mod}.{a.name}" in modules else mod for a in node.names]


def _edges():
    """``(importer unit, imported unit) -> [files]`` over all ideas_hpc imports."""
    modules = _modules()
    edges = defaultdict(set)
    for f in modules.values():
        src = _unit(f)
        for node in ast.walk(ast.parse(f.read_text(), str(f))):
            if not isinstance(node, (ast.Import, ast.ImportFrom)):
                continue
            for name in _imported(f, node, modules):
                if not name.startswith("ideas_hpc"):
                    continue
                # the longest module prefix is what gets loaded (a name imported
                # from a package may be a submodule or an attribute)
                parts = name.split(".")
                while parts and ".".join(parts) not in modules:
                    parts.pop()
                if not parts:
                    continue
                dst = _unit(modules[".".join(parts)])
                if dst != src:
                    edges[(src, dst)].add(f.relative_to(PACKAGE).as_posix())
    return edges


def test_every_folder_has_a_layer():
    ranks = _rank_table()
    units = {_unit(f) for f in _modules().values()}
    missing = sorted(u for u in units if u not in ranks)
    assert not missing, f"folders with no layer in LAYERS: {missing}"


def test_no_import_runs_up():
    ranks = _rank_table()
    up = [f"{a or 'ideas_hpc'} ({LAYERS[ranks[a]][0]}) imports {b or 'ideas_hpc'} "
          f"({LAYERS[ranks[b]][0]}) in {sorted(fs)}"
          for (a, b), fs in sorted(_edges().items()) if ranks[a] < ranks[b]]
    assert not up, "imports that run up a layer:\n" + "\n".join(up)


def _cycles(graph):
    """Strongly connected components with more than one node (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in list(graph):
        if v not in index:
            visit(v)
    return out


def test_no_cycle_between_folders():
    graph = defaultdict(set)
    for a, b in _edges():
        graph[a].add(b)
    cycles = _cycles(graph)
    assert not cycles, f"folders that import each other: {cycles}"


@pytest.mark.parametrize("graph, expect", [
    ({"a": {"b"}, "b": {"c"}}, []),
    ({"a": {"b"}, "b": {"c"}, "c": {"a"}}, [["a", "b", "c"]]),
    ({"a": {"b"}, "b": {"a"}, "c": {"d"}}, [["a", "b"]]),
])
def test_cycle_finder_sees_cycles(graph, expect):
    assert sorted(_cycles(graph)) == expect


def test_edge_reader_sees_relative_and_lazy_imports(tmp_path, monkeypatch):
    """A lazy, relative import from a low folder to a high one is an arrow up."""
    pkg = tmp_path / "ideas_hpc"
    for d in ("", "core", "campaign"):
        (pkg / d).mkdir(parents=True, exist_ok=True)
        (pkg / d / "__init__.py").write_text("")
    (pkg / "campaign" / "run.py").write_text("X = 1\n")
    (pkg / "core" / "k.py").write_text("def f():\n    from ..campaign import run\n")
    monkeypatch.setitem(globals(), "PACKAGE", pkg)
    assert _edges() == {("core", "campaign"): {"core/k.py"}}
    with pytest.raises(AssertionError, match="core .* imports campaign"):
        test_no_import_runs_up()


def test_no_kind_name_is_compared_outside_the_kinds_registry():
    """Kinds declare capabilities (``campaign/schema/kinds.py``); code reads those, so a
    new kind needs no edit elsewhere. A comparison with a registered kind's name is refused."""
    from ideas_hpc.campaign.schema.kinds import KINDS

    names = set(KINDS)
    hits = []
    roots = (PACKAGE, PACKAGE.parent / "analysis")
    for f in (p for r in roots for p in r.rglob("*.py")):
        if f.name == "kinds.py":
            continue
        for node in ast.walk(ast.parse(f.read_text(), str(f))):
            if isinstance(node, ast.Compare):
                consts = [c for c in ast.walk(node) if isinstance(c, ast.Constant)]
            elif isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "startswith":
                consts = [c for c in node.args if isinstance(c, ast.Constant)]
                consts = [c for c in consts if any(n.startswith(str(c.value)) for n in names)
                          and str(c.value) not in ("",)]
                hits += [f"{f.name}:{node.lineno}" for c in consts
                         if isinstance(node.func.value, ast.Attribute)
                         and node.func.value.attr == "kind"]
                continue
            else:
                continue
            hits += [f"{f.name}:{node.lineno}" for c in consts if c.value in names
                     and c.value != "flyby" or (c.value == "flyby" and _is_kind(node))]
    assert not hits, f"kind names compared outside the registry: {hits}"


#: Registered names that are also words of another vocabulary (the paper's geometry
#: and coverage mode; simulate_attitude's start relative to the reference): refused
#: only in a comparison that reads an ``attitude_start``.
SHARED_WORDS = ("paper", "reference")


def _registry_names() -> set:
    from ideas_hpc.attitude.maneuvers import MANEUVERS
    from ideas_hpc.attitude.modes import ATTITUDE_MODES, ATTITUDE_STARTS

    maneuvers = {n for m in MANEUVERS.values() for n in (m.name, m.campaign_name)}
    return set(ATTITUDE_MODES) | set(ATTITUDE_STARTS) | maneuvers


def _registry_comparisons(roots, names, skip=("modes.py", "maneuvers.py")) -> list:
    hits = []
    for f in (p for r in roots for p in r.rglob("*.py")):
        if f.name in skip and f.parent.name == "attitude":
            continue
        for node in ast.walk(ast.parse(f.read_text(), str(f))):
            if not isinstance(node, ast.Compare):
                continue
            for c in ast.walk(node):
                if not (isinstance(c, ast.Constant) and c.value in names):
                    continue
                if c.value not in SHARED_WORDS or _reads(node, "attitude_start"):
                    hits.append(f"{f.name}:{node.lineno} ({c.value!r})")
    return hits


def _reads(node, name: str) -> bool:
    return any(isinstance(n, ast.Attribute) and n.attr == name
               or isinstance(n, ast.Name) and n.id == name for n in ast.walk(node))


def test_no_attitude_mode_start_or_maneuver_name_is_compared_outside_its_registry():
    """Attitude modes and starts (``attitude/modes.py``) and maneuvers
    (``attitude/maneuvers.py``) declare capabilities (``closed_loop``, ``random_state``,
    ``acquisition``, ``nominal_random``, ``usable_images``, ``tracks_body``, ``sweeps``);
    code reads those, so a new entry needs no edit elsewhere (issue 40)."""
    hits = _registry_comparisons((PACKAGE, PACKAGE.parent / "analysis"), _registry_names())
    assert not hits, f"attitude mode, start or maneuver names compared outside: {hits}"


def test_the_registry_scan_sees_comparisons(tmp_path):
    """The scan itself: each way of comparing a name is found, a shared word only
    where it reads an attitude start."""
    (tmp_path / "m.py").write_text(
        'a = setup.attitude_mode == "simulated"\n'
        'b = mc.attitude_start in ("acquisition", "x")\n'
        'c = options.mode == "paper"\n'
        'd = cfg.attitude_start != "paper"\n'
        'e = design == "nadir"\n')
    hits = _registry_comparisons((tmp_path,), _registry_names())
    assert [h.split(" ")[0] for h in hits] == ["m.py:1", "m.py:2", "m.py:4", "m.py:5"]


def _is_kind(node) -> bool:
    """A comparison that reads a ``kind`` (``flyby`` is also a table's name)."""
    return any(isinstance(n, ast.Attribute) and n.attr == "kind"
               or isinstance(n, ast.Name) and n.id == "kind" for n in ast.walk(node))


def test_no_module_imports_another_folders_private_names():
    """A name with a leading underscore stays in its folder: the layers above get a
    public name for what they share (``engine.runner.run_chunk``,
    ``mapping.coverage.mesh_record``)."""
    modules = _modules()
    hits = []
    for f in modules.values():
        for node in ast.walk(ast.parse(f.read_text(), str(f))):
            if not isinstance(node, ast.ImportFrom):
                continue
            for name, alias in zip(_imported(f, node, modules), node.names):
                if not alias.name.startswith("_") or alias.name.endswith("__") \
                        or name.endswith("." + alias.name):
                    continue         # a public name, or a module (``import x as _x``)
                if name in modules and _unit(modules[name]) != _unit(f):
                    hits.append(f"{f.relative_to(PACKAGE)}:{node.lineno} {alias.name}")
    assert not hits, f"private names imported from another folder: {hits}"


#: Most parameters of a function outside ``core/`` (positional and keyword,
#: ``*args`` and ``**kw`` counted once each, ``self``/``cls`` not): more travel
#: together in a frozen settings object (issue 30).
MAX_PARAMETERS = 10


def _parameter_counts(root):
    out = []
    for f in root.rglob("*.py"):
        rel = f.relative_to(root).as_posix()
        if rel.startswith("core/"):
            continue
        for node in ast.walk(ast.parse(f.read_text(), str(f))):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            a = node.args
            names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs]
            names += [x.arg for x in (a.vararg, a.kwarg) if x is not None]
            n = len([x for x in names if x not in ("self", "cls")])
            out.append((rel, node.lineno, node.name, n))
    return out


def test_no_function_outside_core_takes_more_than_ten_parameters():
    over = [f"{rel}:{line} {name} ({n})" for rel, line, name, n in _parameter_counts(PACKAGE)
            if n > MAX_PARAMETERS]
    assert not over, "functions with more than 10 parameters (group them in a settings " \
                     "object):\n" + "\n".join(sorted(over))


def test_parameter_counter_counts_every_kind_of_parameter(tmp_path):
    (tmp_path / "m.py").write_text(
        "class A:\n    def f(self, a, /, b, *c, d, e=1, **f):\n        pass\n")
    assert [(n, k) for _, _, n, k in _parameter_counts(tmp_path)] == [("f", 6)]


#: Most modules at the top of ``ideas_hpc/`` (issue 40): the top level shows the layers
#: (folders) and the CLI; the ground-floor helpers live in ``base/``.
MAX_TOP_MODULES = 8


def test_the_top_level_shows_only_the_layers_and_the_cli():
    top = sorted(f.name for f in PACKAGE.glob("*.py"))
    assert len(top) <= MAX_TOP_MODULES, f"{len(top)} modules at the top of ideas_hpc: {top}"
