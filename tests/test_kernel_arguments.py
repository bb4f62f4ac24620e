"""Issue 21 item 4: kernels take records, so none takes more than 12 arguments.

Counted on the source (an ``ast`` walk over every function decorated with ``njit``),
independently of the kernels themselves.
"""

import ast
from pathlib import Path

import ideas_hpc

CORE = Path(ideas_hpc.__file__).parent / "core"
LIMIT = 12


def _njit_arity(path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef) and any(
                "njit" in ast.unparse(d) for d in node.decorator_list):
            yield node.name, len(node.args.args) + len(node.args.kwonlyargs)


def test_kernels_take_at_most_12_arguments():
    over = [f"{p.relative_to(CORE)}::{name} ({n})" for p in sorted(CORE.rglob("*.py"))
            for name, n in _njit_arity(p) if n > LIMIT]
    assert not over, f"kernels over {LIMIT} arguments: {over}"


def test_the_count_sees_a_long_signature(tmp_path):
    """The walk itself: a 13-argument njit function is counted as 13."""
    src = tmp_path / "k.py"
    args = ", ".join(f"a{i}" for i in range(13))
    src.write_text(f"from numba import njit\n\n@njit(cache=True)\ndef k({args}):\n    return a0\n")
    assert dict(_njit_arity(src)) == {"k": 13}
