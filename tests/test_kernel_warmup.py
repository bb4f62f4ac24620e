"""CI's kernel warm-up (tests/kernel_warmup.py): its list names the package's kernels,
and what it compiles is what a later process loads instead of compiling.

Oracle: Numba's own ``Dispatcher.stats`` (cache hits and misses) in a fresh process.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import kernel_warmup as kw

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent

_CALL = """
import json, sys
sys.path.insert(0, {tests!r})
import kernel_warmup as kw
from ideas_hpc.core.dynamics.frames import dcm_RS
counts = kw.compile_rows(kw.read_list()[:1]) if sys.argv[1] == "warm" else None
dcm_RS(0.3)
print(json.dumps({{"counts": counts, "hits": sum(dcm_RS.stats.cache_hits.values()),
                   "misses": sum(dcm_RS.stats.cache_misses.values())}}))
"""


def _run(step: str, cache: Path) -> dict:
    env = dict(os.environ, IDEAS_HPC_KERNEL_CACHE=str(cache),
               PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    env.pop("NUMBA_CACHE_DIR", None)
    out = subprocess.run([sys.executable, "-c", _CALL.format(tests=str(TESTS)), step], env=env,
                         capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_every_listed_signature_names_a_cached_kernel_of_the_package():
    """A renamed or removed kernel leaves a row that compiles nothing: rewrite the list
    (``python tests/kernel_warmup.py record`` after a full run)."""
    rows = kw.read_list()
    assert len(rows) > 100
    kernels = {(m, q) for m, q, _ in kw.cached_dispatchers()}
    stale = sorted({f"{m}.{q}" for m, q, _ in rows} - {f"{m}.{q}" for m, q in kernels})
    assert not stale, stale
    for _, _, text in rows:
        assert isinstance(kw.decode(text), tuple)       # a signature: a tuple of types


def test_what_the_warm_up_compiled_a_later_process_loads(tmp_path):
    # the list's first row is the leaf dcm_RS(float64) (callees are written first)
    assert kw.read_list()[0][:2] == ("ideas_hpc.core.dynamics.frames", "dcm_RS")
    cold = _run("cold", tmp_path / "cold")
    assert cold["misses"] == 1 and cold["hits"] == 0        # the oracle sees a compile
    warm = _run("warm", tmp_path / "warm")
    assert warm["counts"] == {"compiled": 1, "cached": 0, "skipped": 0}
    later = _run("cold", tmp_path / "warm")
    assert later["hits"] == 1 and later["misses"] == 0
    again = _run("warm", tmp_path / "warm")                 # nothing compiled twice
    assert again["counts"] == {"compiled": 0, "cached": 1, "skipped": 0}
