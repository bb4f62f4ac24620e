"""Kernels shared by checkouts of the same sources (:mod:`ideas_hpc.base.kernel_cache`).

The oracle is Numba's own bookkeeping: ``Dispatcher.stats`` counts a signature loaded
from the on-disk cache as a hit and a compiled one as a miss. Two copies of a two-file
package (kernel ``a.twice`` calls kernel ``b.base``) at different paths stand for two
clones: the second must load what the first compiled, write nothing beside its own
sources, and, once one byte of the callee differs, compile the new callee (the value
says which callee ran).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from ideas_hpc.base.kernel_cache import ENV, prune

ROOT = Path(__file__).resolve().parent.parent

PROBE = ("import json; from kern.a import twice; v = twice(1.0); "
         "s = twice.stats; print(json.dumps({'value': v, 'hits': sum(s.cache_hits.values()), "
         "'misses': sum(s.cache_misses.values())}))")


def _package(root: Path, value: float) -> None:
    pkg = root / "kern"
    pkg.mkdir(parents=True, exist_ok=True)
    (pkg / "__init__.py").write_text("from ideas_hpc.base.kernel_cache import share\n"
                                     "share(__path__[0])\n")
    (pkg / "b.py").write_text(textwrap.dedent(f"""\
        from numba import njit

        @njit(cache=True)
        def base(x):
            return x + {value!r}
        """))
    (pkg / "a.py").write_text(textwrap.dedent("""\
        from numba import njit
        from kern.b import base

        @njit(cache=True)
        def twice(x):
            return 2.0 * base(x)
        """))


def _run(root: Path, **env_extra) -> dict:
    env = {**os.environ, "PYTHONPATH": f"{root}{os.pathsep}{ROOT}", **env_extra}
    for k in ("NUMBA_CACHE_DIR", "NUMBA_CACHE_LOCATOR_CLASSES"):
        if k not in env_extra:
            env.pop(k, None)
    out = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True,
                         text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _in_tree(root: Path) -> list[Path]:
    return sorted(root.rglob("*.nbi"))


def test_a_second_checkout_loads_what_the_first_compiled(tmp_path):
    shared = tmp_path / "shared"
    one, two = tmp_path / "clone1", tmp_path / "clone2"
    _package(one, 1.0)
    _package(two, 1.0)
    first = _run(one, **{ENV: str(shared)})
    assert first == {"value": 4.0, "hits": 0, "misses": 1}       # compiled: 2 (1 + 1)
    second = _run(two, **{ENV: str(shared)})
    assert second == {"value": 4.0, "hits": 1, "misses": 0}      # loaded, not compiled
    assert _in_tree(one) == [] and _in_tree(two) == []           # nothing beside the sources
    assert len([p for p in shared.iterdir() if p.is_dir()]) == 1

    # one byte of the callee differs in clone2: another version, compiled, the new callee
    (two / "kern" / "b.py").write_text((two / "kern" / "b.py").read_text().replace("1.0", "10.0"))
    changed = _run(two, **{ENV: str(shared)})
    assert changed == {"value": 22.0, "hits": 0, "misses": 1}    # 2 (1 + 10)
    assert _run(two, **{ENV: str(shared)}) == {"value": 22.0, "hits": 1, "misses": 0}
    assert _run(one, **{ENV: str(shared)}) == {"value": 4.0, "hits": 1, "misses": 0}
    assert len([p for p in shared.iterdir() if p.is_dir()]) == 2


def test_tree_and_numba_cache_dir_keep_their_places(tmp_path):
    shared, numba_dir = tmp_path / "shared", tmp_path / "numba"
    tree = tmp_path / "tree"
    _package(tree, 1.0)
    assert _run(tree, **{ENV: "tree"})["misses"] == 1
    assert len(_in_tree(tree)) == 2 and not shared.exists()      # Numba's in-tree caches
    for f in _in_tree(tree):
        f.unlink()
    assert _run(tree, **{ENV: str(shared), "NUMBA_CACHE_DIR": str(numba_dir)})["misses"] == 1
    assert len(_in_tree(numba_dir)) == 2 and _in_tree(tree) == []   # NUMBA_CACHE_DIR wins
    assert _in_tree(shared) == []


def test_prune_keeps_the_recent_and_the_busy(tmp_path):
    now = time.time()
    ages_s = [0, 10, 20, 30, 40, 50, 60, 2 * 86400, 3 * 86400]   # 9 versions, newest first
    for i, age in enumerate(ages_s):
        p = tmp_path / f"v{i}"
        (p / "sub").mkdir(parents=True)
        os.utime(p, (now - age, now - age))
    removed = prune(tmp_path, keep=6, min_idle_s=86400.0)
    # beyond the 6 newest: v6 (used a minute ago: may be running, kept), v7 and v8 (removed)
    assert sorted(p.name for p in removed) == ["v7", "v8"]
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"v{i}" for i in range(7)]
    shutil.rmtree(tmp_path / "v0")
    assert prune(tmp_path, keep=6, min_idle_s=86400.0) == []
