"""Compile once across processes (issue 43): a second process that needs a kernel another
one is compiling waits for it and loads it from the cache instead of compiling it again."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

KERNEL = textwrap.dedent("""
    from numba import njit

    @njit(cache=True)
    def kernel(x):
        s = 0.0
        for i in range(10):
            s += x * i
        return s
""")

CHILD = textwrap.dedent("""
    import json, sys
    import ideas_hpc.core                  # installs the per-kernel compile lock
    import k43
    print("ready", flush=True)             # next: the first call, which needs a compile
    value = k43.kernel(2.0)
    st = k43.kernel.stats
    print(json.dumps({"value": value, "hits": sum(st.cache_hits.values()),
                      "misses": sum(st.cache_misses.values())}), flush=True)
""")


def test_a_process_waits_for_the_kernel_another_compiles_and_loads_it(tmp_path):
    """This process holds the kernel's lock (as its compile does) while a child reaches its
    first call, then compiles and writes the cache; the child must load it (one cache hit,
    no miss): without the lock it would find the cache empty and compile it too."""
    (tmp_path / "k43.py").write_text(KERNEL)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]),
               NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    code = ("import os, sys; os.environ['NUMBA_CACHE_DIR'] = sys.argv[1]; "
            "sys.path[:0] = [sys.argv[2]]; import ideas_hpc.core, k43; "
            "from ideas_hpc.base import compile_once; " + _HERE)
    here = subprocess.Popen([sys.executable, "-c", code, env["NUMBA_CACHE_DIR"], str(tmp_path)],
                            env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    child = None
    try:
        assert here.stdout.readline().strip() == "locked"
        child = subprocess.Popen([sys.executable, "-c", CHILD], env=env,
                                 stdout=subprocess.PIPE, text=True)
        assert child.stdout.readline().strip() == "ready"
        here.stdin.write("go\n")
        here.stdin.flush()
        mine = json.loads(here.stdout.readline())
        theirs = json.loads(child.stdout.readline())
    finally:
        for p in (here, child):
            if p is not None and p.poll() is None:
                p.kill()
            if p is not None:
                p.wait()
    assert mine["misses"] == 1 and mine["hits"] == 0       # this one compiled it
    assert theirs["misses"] == 0 and theirs["hits"] == 1   # the child loaded it
    assert theirs["value"] == mine["value"] == sum(2.0 * i for i in range(10))


#: The holder: takes the kernel's lock, says so, waits for "go", compiles (under the
#: lock), then releases it by leaving the block.
_HERE = ("import json\n"
         "with compile_once.holding(k43.kernel):\n"
         "    print('locked', flush=True)\n"
         "    sys.stdin.readline()\n"
         "    v = k43.kernel(2.0)\n"
         "    st = k43.kernel.stats\n"
         "    out = json.dumps({'value': v, 'hits': sum(st.cache_hits.values()), "
         "'misses': sum(st.cache_misses.values())})\n"
         "print(out, flush=True)\n")
