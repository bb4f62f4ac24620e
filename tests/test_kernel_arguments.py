"""Issue 21 item 4, issue 40 item 7: kernels take records, so none takes more than 12
arguments, the CUDA kernels included.

Counted on the source (an ``ast`` walk over every function decorated with ``njit`` or
``cuda.jit``), independently of the kernels themselves.
"""

import ast
from pathlib import Path

import ideas_hpc

CORE = Path(ideas_hpc.__file__).parent / "core"
LIMIT = 12


def _compiled(decorator) -> bool:
    """``@njit``, ``@njit(...)``, ``@numba.njit``, ``@cuda.jit``, ``@cuda.jit(...)``."""
    text = ast.unparse(decorator)
    return "njit" in text or "cuda.jit" in text


def _njit_arity(path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef) and any(
                _compiled(d) for d in node.decorator_list):
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


def test_the_count_sees_cuda_kernels(tmp_path):
    """A ``numba.cuda`` kernel and device function are counted as the CPU kernels are."""
    src = tmp_path / "k.py"
    args = ", ".join(f"a{i}" for i in range(27))
    src.write_text("from numba import cuda\n\n@cuda.jit\n"
                   f"def k({args}):\n    pass\n\n@cuda.jit(device=True)\n"
                   "def d(a, b):\n    return a\n")
    assert dict(_njit_arity(src)) == {"k": 27, "d": 2}


def test_the_cuda_kernel_is_counted():
    """The walk reaches ``core/attitude/batch_cuda.py``'s kernel (it has no ``njit``)."""
    names = dict(_njit_arity(CORE / "attitude" / "batch_cuda.py"))
    assert "_flights" in names and "_reference" in names
