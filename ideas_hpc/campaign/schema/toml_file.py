"""TOML campaign files: loading, ``--set`` overrides, and field/line bookkeeping.

A campaign file is read once. ``--set dotted.key=value`` overrides are applied
on top (the value is parsed as a TOML value, so ``--set swarm.n_max=12``,
``--set body.name="eros"`` and ``--set controller.k_p=[4, 0.4, 0.4]`` all work;
a bare word that is not valid TOML is taken as a string). Every error raised
while validating is an :class:`~ideas_hpc.base.errors.InputError` that names the
dotted field and, when the value came from the file, the file and line.
"""

from __future__ import annotations

import copy
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ideas_hpc.base.errors import InputError

_HEADER = re.compile(r"^\s*\[\s*([^\[\]]+?)\s*\]\s*(#.*)?$")
_ARRAY_HEADER = re.compile(r"^\s*\[\[\s*([^\[\]]+?)\s*\]\]\s*(#.*)?$")
_KEY = re.compile(r"^\s*([A-Za-z0-9_\-\.\"']+)\s*=")


def _norm_key(k: str) -> str:
    return ".".join(p.strip().strip('"').strip("'") for p in k.split("."))


def line_index(text: str) -> dict[str, int]:
    """Map dotted keys (tables and ``key = value`` lines) to 1-based line numbers.

    A light scan, not a parser: it understands ``[table]`` headers, dotted keys
    and plain keys, which is what campaign files use. Keys it cannot place are
    simply absent, and errors then name the field without a line.
    """
    idx: dict[str, int] = {}
    prefix = ""
    depth = 0  # inside a multi-line array or inline table: skip nested lines
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0] if '"' not in raw and "'" not in raw else raw
        if depth > 0:
            depth += line.count("[") + line.count("{") - line.count("]") - line.count("}")
            continue
        m = _ARRAY_HEADER.match(line) or _HEADER.match(line)
        if m:
            prefix = _norm_key(m.group(1))
            idx.setdefault(prefix, lineno)
            continue
        m = _KEY.match(line)
        if m:
            key = _norm_key(m.group(1))
            full = f"{prefix}.{key}" if prefix else key
            idx.setdefault(full, lineno)
            rest = line[m.end():]
            depth = rest.count("[") + rest.count("{") - rest.count("]") - rest.count("}")
            depth = max(depth, 0)
    return idx


@dataclass
class CampaignSource:
    """A loaded campaign: the merged data and where each field came from."""

    data: dict
    path: Path | None = None
    lines: dict[str, int] = field(default_factory=dict)
    overrides: list[str] = field(default_factory=list)
    #: A store's resolved config (every default written out): no key of it counts as
    #: set by a user, so the keys its kind reads are not judged.
    resolved: bool = False

    def where(self, dotted: str) -> tuple[str | None, int | None]:
        """``(file, line)`` of a dotted field, or of its nearest enclosing table.

        Overridden fields report ``--set`` instead of a file line.
        """
        keys = [ov.split("=", 1)[0].strip() for ov in self.overrides]
        if dotted.split("[")[0] in keys:  # swarm.angles_rad[1] came with swarm.angles_rad
            return "--set", None
        if dotted not in self.lines and any(k.startswith(dotted + ".") for k in keys):
            return "--set", None  # a table only --set introduced (a typo there)
        key = dotted
        while key:
            if key in self.lines:
                return (str(self.path) if self.path else None), self.lines[key]
            key = key.rpartition(".")[0]
        return (str(self.path) if self.path else None), None

    def error(self, message: str, dotted: str) -> InputError:
        """An :class:`InputError` for ``dotted`` with file and line filled in."""
        f, ln = self.where(dotted)
        return InputError(message, field=dotted, file=f, line=ln)

    def locate(self, exc: InputError) -> InputError:
        """Add file and line to an error raised with only a field name."""
        if exc.file is not None or not exc.field:
            return exc
        return self.error(exc.message, exc.field)


def parse_override(text: str) -> tuple[list[str], Any]:
    """Split ``dotted.key=value`` into the key path and a TOML-parsed value."""
    if "=" not in text:
        raise InputError(f"--set needs dotted.key=value, got {text!r}", field="--set")
    key, _, raw = text.partition("=")
    key = key.strip()
    if not key or any(not p.strip() for p in key.split(".")):
        raise InputError(f"--set has an empty key part in {text!r}", field="--set")
    raw = raw.strip()
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        if raw == "" or any(c in raw for c in "[]{}\"'="):
            raise InputError(f"cannot parse the value of {key!r}: {raw!r} is not a TOML value",
                             field=key, file="--set") from None
        value = raw  # a bare word such as eros001708
    return [p.strip() for p in key.split(".")], value


def apply_overrides(data: dict, overrides: list[str]) -> dict:
    """Return a deep copy of ``data`` with every ``dotted.key=value`` applied in order.

    Intermediate tables are created as needed; setting a key inside a value
    that is not a table is an error naming the key.
    """
    out = copy.deepcopy(data)
    for text in overrides or []:
        path, value = parse_override(text)
        node = out
        for i, part in enumerate(path[:-1]):
            nxt = node.get(part)
            if nxt is None:
                nxt = node[part] = {}
            elif not isinstance(nxt, dict):
                raise InputError(f"{'.'.join(path[:i + 1])} is a value, not a table, so "
                                 f"{'.'.join(path)} cannot be set", field=".".join(path),
                                 file="--set")
            node = nxt
        node[path[-1]] = value
    return out


def load_campaign(path, overrides: list[str] | None = None) -> CampaignSource:
    """Read a TOML campaign file and apply ``--set`` overrides.

    Raises
    ------
    InputError
        For a missing file or a TOML syntax error (with the file and line).
    """
    p = Path(path)
    if not p.is_file():
        raise InputError("campaign file not found", file=p)
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        line = p.read_bytes()[:exc.start].count(b"\n") + 1
        raise InputError(f"not a UTF-8 text file (byte {exc.start}); a campaign file is TOML "
                         "text", file=p, line=line) from None
    except OSError as exc:
        raise InputError(f"cannot read the campaign file: {exc.strerror}", file=p) from None
    if text.startswith("\ufeff"):   # a UTF-8 byte-order mark (some Windows editors): not TOML
        text = text[1:]
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"line (\d+)", str(exc))
        raise InputError(f"TOML syntax error: {exc}", file=p,
                         line=int(m.group(1)) if m else None) from None
    overrides = list(overrides or [])
    return CampaignSource(apply_overrides(data, overrides), p, line_index(text), overrides)


def get_path(data: dict, dotted: str, default: Any = None) -> Any:
    """``data['a']['b']`` for ``'a.b'``, or ``default`` when any part is absent."""
    node: Any = data
    for part in dotted.split("."):
        if not isinstance(node, dict) or part not in node:
            return default
        node = node[part]
    return node
