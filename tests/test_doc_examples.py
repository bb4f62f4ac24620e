"""The README's and the docs' examples cannot go stale: every ``ideas-hpc`` command block
is run, and the output lines the text quotes after it must be among the lines printed.

How a page is read (see :func:`examples`):

* a fenced ``bash``/``sh``/``console`` block with lines starting ``ideas-hpc `` is an
  example; its ``ideas-hpc`` lines run in order, in a scratch folder that sees the
  repository's ``campaigns/`` and ``docs/`` (other lines, e.g. ``pip install``, do not run);
* the first fenced ``text`` block after it (before the next example or heading) is the
  output the text quotes for the example's last command: every non-blank line must
  equal, up to runs of whitespace, a line printed on stdout or stderr; ``...`` in a
  quoted line stands for any text (numbers that depend on the body, timings);
* an HTML comment on the line before the block or after it steers the run:
  ``<!-- docs-test: skip (why) -->``, ``<!-- docs-test: fast -->`` (in the default
  suite; ``run`` and ``scan-*`` examples are otherwise ``slow``) and ``--set KEY=VALUE``
  overrides appended to every ``run``/``scan-*`` command of the block, to make an
  expensive example small (the text should say so).
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
FENCE = re.compile(r"^(```+|~~~+)\s*\{?([\w-]*)\}?")
MARKER = re.compile(r"<!--\s*docs-test:(.*?)-->")
SHELL = {"bash", "sh", "shell", "console"}
EXPENSIVE = {"run", "scan-arrival", "scan-encounter"}


@dataclass
class Example:
    """One command block of a page: where it is, what it runs, what it quotes."""

    page: str
    line: int
    commands: list[list[str]]
    expected: list[str] = field(default_factory=list)
    skip: str | None = None
    fast: bool = False
    overrides: list[str] = field(default_factory=list)

    @property
    def id(self) -> str:
        return f"{self.page}:{self.line}"


def _blocks(text: str):
    """(start line, language, body lines, line after the block) of every fenced block."""
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i].strip())
        if m:
            fence, lang = m.group(1), m.group(2).lower()
            j = i + 1
            while j < len(lines) and not lines[j].strip().startswith(fence):
                j += 1
            yield i, lang, lines[i + 1:j], j + 1
            i = j + 1
        else:
            i += 1


def _marker(lines: list[str], at: int, step: int) -> str | None:
    """The docs-test comment on the nearest non-blank line from ``at`` going ``step``."""
    k = at
    while 0 <= k < len(lines) and not lines[k].strip():
        k += step
    if 0 <= k < len(lines):
        m = MARKER.search(lines[k])
        if m:
            return m.group(1).strip()
    return None


def parse_page(path: Path) -> list[Example]:
    """The examples of one Markdown page, with their quoted output and markers."""
    text = path.read_text(encoding="utf-8")
    lines = text.splitlines()
    page = str(path.relative_to(ROOT))
    found: list[Example] = []
    current: Example | None = None
    for start, lang, body, after in _blocks(text):
        heading_between = current is not None and any(
            ln.startswith("#") for ln in lines[current.line:start])
        if lang in SHELL:
            cmds = [shlex.split(ln.strip()) for ln in body if ln.strip().startswith("ideas-hpc ")]
            if not cmds:
                continue
            ex = Example(page, start + 1, cmds)
            for mark in filter(None, (_marker(lines, start - 1, -1), _marker(lines, after, 1))):
                if mark.startswith("skip"):
                    ex.skip = mark[4:].strip(" ()") or "marked skip"
                    continue
                ex.fast = ex.fast or mark.split()[0:1] == ["fast"]
                words = shlex.split(mark)
                ex.overrides += [w for k, w in enumerate(words) if k and words[k - 1] == "--set"]
            found.append(ex)
            current = ex
        elif lang == "text" and current is not None and not current.expected \
                and not heading_between:
            current.expected = [ln for ln in body if ln.strip()]
    return found


def examples() -> list[Example]:
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    return [ex for p in pages if "_build" not in p.parts for ex in parse_page(p)]


def _pattern(quoted: str) -> re.Pattern:
    """A quoted line as a pattern: runs of whitespace equal, ``...`` any text."""
    parts = [re.escape(" ".join(piece.split())) for piece in quoted.split("...")]
    return re.compile("^" + ".*".join(parts) + "$")


def quoted_lines_missing(expected: list[str], printed: str) -> list[str]:
    """The quoted lines that no printed line matches."""
    lines = [" ".join(ln.split()) for ln in printed.replace("\r", "\n").splitlines()]
    return [q for q in expected if not any(_pattern(q).match(ln) for ln in lines)]


def _params():
    out = []
    for ex in examples():
        marks = []
        if ex.skip:
            marks.append(pytest.mark.skip(reason=ex.skip))
        elif not ex.fast and any(c[1:2] and c[1] in EXPENSIVE for c in ex.commands):
            marks.append(pytest.mark.slow)
        out.append(pytest.param(ex, id=ex.id, marks=marks))
    return out


# ---- the reader itself, on a page with known answers ----

PAGE = """# t

```bash
pip install x
ideas-hpc size --paper
```

Some prose.

```text
max sweep angle theta_max   1.9136  deg
```

<!-- docs-test: --set design.n_max=2 -->
```bash
ideas-hpc run campaigns/a.toml --out a.zarr
```

## heading

```text
not quoted by the run above
```

```bash
ideas-hpc report a.zarr
```
<!-- docs-test: skip (too long) -->
"""


def test_reader_finds_commands_quotes_and_markers(tmp_path, monkeypatch):
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    page = tmp_path / "p.md"
    page.write_text(PAGE)
    a, b, c = parse_page(page)
    assert a.commands == [["ideas-hpc", "size", "--paper"]]
    assert a.expected == ["max sweep angle theta_max   1.9136  deg"]
    assert b.overrides == ["design.n_max=2"] and b.expected == [] and not b.skip
    assert c.skip == "too long"


def test_quoted_lines_match_up_to_whitespace_and_ellipsis():
    printed = "a  b\r  max sweep angle theta_max     1.9136  deg\nN = 5, P = 0.94\n"
    assert quoted_lines_missing(["max sweep angle theta_max 1.9136 deg"], printed) == []
    assert quoted_lines_missing(["N = ..., P = ..."], printed) == []
    assert quoted_lines_missing(["max sweep angle theta_max 1.9137 deg"], printed) \
        == ["max sweep angle theta_max 1.9137 deg"]
    assert quoted_lines_missing(["N = 5"], printed) == ["N = 5"]  # whole lines only


def test_the_docs_have_examples():
    exs = examples()
    assert any(ex.page == "README.md" and ex.expected for ex in exs)


# ---- the examples ----

@pytest.mark.parametrize("ex", _params())
def test_example_runs_and_prints_what_the_text_quotes(ex: Example, tmp_path):
    for name in ("campaigns", "docs"):
        (tmp_path / name).symlink_to(ROOT / name)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])), MPLBACKEND="Agg")
    printed = ""
    for cmd in ex.commands:
        argv = [sys.executable, "-m", "ideas_hpc.cli", *cmd[1:]]
        if cmd[1:2] and cmd[1] in EXPENSIVE:
            argv += [a for o in ex.overrides for a in ("--set", o)]
        proc = subprocess.run(argv, cwd=tmp_path, env=env, capture_output=True, text=True,
                              timeout=1800)
        assert proc.returncode == 0, (f"{ex.id}: {shlex.join(cmd)} exited {proc.returncode}:\n"
                                      f"{proc.stderr[-3000:]}")
        printed = proc.stdout + "\n" + proc.stderr
    missing = quoted_lines_missing(ex.expected, printed)
    assert not missing, (f"{ex.id}: the text quotes lines the last command did not print: "
                         f"{missing}\n--- printed ---\n{printed[-3000:]}")
