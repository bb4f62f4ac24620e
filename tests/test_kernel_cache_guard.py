"""Stale kernel caches (:func:`ideas_hpc.base.compile_once.guard_sources`).

Numba checks a cached kernel against its own source file only. The oracle is Numba's own
behaviour on a two-file package: kernel ``a.twice`` calls kernel ``b.base``; after ``b.py``
changes (``a.py`` untouched, as after a pull that edits a callee), a fresh process must
compute with the new callee. Without the guard it runs the cached old machine code (the
first half of the test shows that it does), with it the new value.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

from ideas_hpc.base.compile_once import STAMP, guard_sources

ROOT = Path(__file__).resolve().parent.parent


def _package(root: Path, guarded: bool, value: float) -> None:
    pkg = root / "kern"
    pkg.mkdir(exist_ok=True)
    init = ("from ideas_hpc.base.compile_once import guard_sources\n"
            "guard_sources(__path__[0])\n") if guarded else ""
    (pkg / "__init__.py").write_text(init)
    (pkg / "b.py").write_text(textwrap.dedent(f"""\
        from numba import njit

        @njit(cache=True)
        def base(x):
            return x + {value!r}
        """))
    if not (pkg / "a.py").exists():       # written once: its mtime never changes
        (pkg / "a.py").write_text(textwrap.dedent("""\
            from numba import njit
            from kern.b import base

            @njit(cache=True)
            def twice(x):
                return 2.0 * base(x)
            """))


def _run(root: Path) -> float:
    env = {**os.environ, "PYTHONPATH": f"{root}{os.pathsep}{ROOT}"}
    env.pop("NUMBA_CACHE_DIR", None)
    out = subprocess.run([sys.executable, "-c", "from kern.a import twice; print(twice(1.0))"],
                         env=env, capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def test_a_changed_callee_is_compiled_again(tmp_path):
    plain, guarded = tmp_path / "plain", tmp_path / "guarded"
    for root, g in ((plain, False), (guarded, True)):
        root.mkdir()
        _package(root, g, 1.0)
        assert _run(root) == 4.0                       # compiled and cached: 2 (1 + 1)
        _package(root, g, 10.0)                        # the callee changes, a.py does not
    assert _run(plain) == 4.0     # Numba alone: the caller's cached code, the old callee
    assert _run(guarded) == 22.0  # the guard: 2 (1 + 10)
    assert _run(guarded) == 22.0  # and again from the cache it wrote


def test_the_guard_removes_caches_only_when_the_sources_change(tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    pkg = tmp_path / "p"
    (pkg / "sub" / "__pycache__").mkdir(parents=True)
    (pkg / "k.py").write_text("x = 1\n")
    (pkg / "sub" / "j.py").write_text("y = 2\n")

    def caches():
        for name in ("j.f-1.py311.nbi", "j.f-1.py311.1.nbc"):
            (pkg / "sub" / "__pycache__" / name).write_bytes(b"cache")

    caches()
    assert guard_sources(pkg) == 2                     # no stamp yet: unknown sources
    assert (pkg / "__pycache__" / STAMP).exists()
    caches()
    assert guard_sources(pkg) == 0                     # same sources: caches kept
    assert len(list(pkg.rglob("*.nb*"))) == 2
    (pkg / "sub" / "j.py").write_text("y = 3\n")
    assert guard_sources(pkg) == 2                     # a source changed: all removed
    caches()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "elsewhere"))
    (pkg / "k.py").write_text("x = 5\n")
    assert guard_sources(pkg) == 0                     # caches live elsewhere: untouched
