"""Declarative validation of campaign tables: types, ranges, units, unknown keys.

A schema is a dict of :class:`Field` (or nested dicts for sub-tables). Values
are checked once, converted to SI with ``Field.to_si`` (or ``Field.per``), and
defaults filled in. Every error names the dotted field; :class:`~ideas_hpc.campaign.schema.toml_file.CampaignSource`
adds the file and line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, make_dataclass
from dataclasses import fields as dc_fields
from typing import Any

import numpy as np

from ideas_hpc.base.errors import InputError

REQUIRED = object()


@dataclass(frozen=True)
class Field:
    """One config value.

    Parameters
    ----------
    kind : {'float', 'int', 'bool', 'str', 'floats', 'any'}
        ``floats`` is a list of numbers (``length`` fixes its size; a scalar
        is broadcast when ``broadcast`` is set).
    default : object
        ``REQUIRED`` when the key must be given.
    to_si : float
        Multiplier from the file's unit to SI (e.g. 1e3 for km).
    per : float, optional
        Divisor from the file's unit to SI instead (100 for a percentage): ``x / 100``
        rounds once, where ``x * 0.01`` rounds twice and differs from it in the last
        bit for about one value in eight, so a percentage converts exactly as the
        code that divided by 100 did.
    lo, hi : float, optional
        Bounds in the file's unit; ``lo_open``/``hi_open`` make them strict.
    choices : tuple, optional
        Allowed values for ``str`` fields.
    doc : str
        One line for error messages and ``--help``.
    si : str, optional
        The name of the validated (SI) value, when the key carries a file unit
        (``aperture_cm`` -> ``aperture_m``); default: the key itself. Typed
        tables (:func:`typed_table`) use it, so names never lie about units.
    """

    kind: str
    default: Any = REQUIRED
    to_si: float = 1.0
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    choices: tuple | None = None
    length: int | None = None
    broadcast: bool = False
    nullable: bool = False
    doc: str = ""
    si: str | None = None
    per: float | None = None

    def si_name(self, key: str) -> str:
        return self.si or key

    def convert(self, x: float) -> float:
        """The SI value of the number ``x`` given in the file's unit."""
        return x / self.per if self.per is not None else x * self.to_si


def _range_msg(f: Field) -> str:
    lo = "" if f.lo is None else ("> " if f.lo_open else ">= ") + f"{f.lo:g}"
    hi = "" if f.hi is None else ("< " if f.hi_open else "<= ") + f"{f.hi:g}"
    return " and ".join(p for p in (lo, hi) if p)


def number(value: Any, field: str, *, lo: float | None = None, hi: float | None = None,
           lo_open: bool = False, hi_open: bool = False) -> float:
    """The one numeric check of every configuration value: a real, finite number in range.

    Every numeric check in the package goes through here (models, designers
    and the campaign tables alike), so a value is judged and worded one way.
    Raises :class:`InputError` naming ``field``; returns ``float(value)``.
    """
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputError(f"must be a number, got {value!r}", field=field)
    x = float(value)
    if not math.isfinite(x):
        raise InputError(f"must be finite, got {value!r}", field=field)
    bad = ((lo is not None and (x <= lo if lo_open else x < lo))
           or (hi is not None and (x >= hi if hi_open else x > hi)))
    if bad:
        f = Field("float", lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open)
        fraction = hi == 1 and lo is not None and 0 <= lo < 1 and x > 1   # 90 for 0.9
        raise InputError(f"must be {_range_msg(f)}, got {x:g}"
                         + (" (a fraction, e.g. 0.9, not a percentage)" if fraction else ""),
                         field=field)
    return x


def _check_number(x: float, f: Field, name: str) -> None:
    number(x, name, lo=f.lo, hi=f.hi, lo_open=f.lo_open, hi_open=f.hi_open)


def _coerce(value: Any, f: Field, name: str) -> Any:
    if value is None and f.nullable:
        return None
    k = f.kind
    if k == "any":
        return value
    if k == "bool":
        if not isinstance(value, bool):
            raise InputError(f"must be true or false, got {value!r}", field=name)
        return value
    if k == "str":
        if not isinstance(value, str):
            raise InputError(f"must be a string, got {value!r}", field=name)
        if f.choices is not None and value not in f.choices:
            raise InputError(f"must be one of {', '.join(map(str, f.choices))}; got {value!r}",
                             field=name)
        return value
    if k == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise InputError(f"must be a whole number, got {value!r}", field=name)
        _check_number(float(value), f, name)
        return int(value)
    if k == "float":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InputError(f"must be a number, got {value!r}", field=name)
        _check_number(float(value), f, name)
        return f.convert(float(value))
    if k == "floats":
        if isinstance(value, (int, float)) and not isinstance(value, bool) and f.broadcast:
            value = [value] * (f.length or 1)
        if not isinstance(value, list):
            raise InputError(f"must be a list of numbers, got {value!r}", field=name)
        if f.length is not None and len(value) != f.length:
            raise InputError(f"must have {f.length} numbers, got {len(value)}", field=name)
        out = []
        for i, v in enumerate(value):
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise InputError(f"item {i} must be a number, got {v!r}", field=name)
            _check_number(float(v), f, f"{name}[{i}]")
            out.append(f.convert(float(v)))
        return out
    raise AssertionError(f"unknown field kind {k!r}")  # schema bug, not user input


def validate(data: Any, schema: dict, prefix: str = "") -> dict:
    """Check ``data`` against ``schema`` and return SI values with defaults filled in.

    Raises
    ------
    InputError
        Naming the first offending dotted field: an unknown key (with the
        allowed ones), a wrong type, a value out of range, a missing key.
    """
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise InputError(f"must be a table, got {data!r}", field=prefix.rstrip(".") or "<root>")
    unknown = [k for k in data if k not in schema]
    if unknown:
        raise InputError(f"unknown key {unknown[0]!r}; allowed here: {', '.join(sorted(schema))}",
                         field=prefix + unknown[0])
    out: dict = {}
    for key, spec in schema.items():
        name = prefix + key
        if isinstance(spec, dict):
            out[key] = validate(data.get(key), spec, name + ".")
            continue
        if key not in data:
            if spec.default is REQUIRED:
                raise InputError(f"is required ({spec.doc})" if spec.doc else "is required",
                                 field=name)
            default = spec.default
            out[key] = (_coerce(default, spec, name) if default is not None else None)
            continue
        out[key] = _coerce(data[key], spec, name)
    return out


def with_defaults(data: Any, schema: dict) -> dict:
    """``data`` with every absent key of ``schema`` filled by its default, in the file's units.

    The counterpart of :func:`validate` for the record of a run: no unit
    conversion, so the result reads like a campaign file with nothing left
    implicit. Call it on data that :func:`validate` accepted. Required keys
    without a value and ``any`` fields are copied as they are.
    """
    data = data if isinstance(data, dict) else {}
    out: dict = {}
    for key, spec in schema.items():
        if isinstance(spec, dict):
            out[key] = with_defaults(data.get(key), spec)
        elif key in data:
            out[key] = data[key]
        elif spec.default is not REQUIRED:
            out[key] = spec.default
    return out


def schema_defaults(schema: dict, prefix: str = "") -> dict[str, Any]:
    """Every key of ``schema`` that has a default, as ``{"table.key": default}`` (file units).

    What a key means when a file (or a store written before the key existed)
    leaves it out; required keys are absent.
    """
    out: dict[str, Any] = {}
    for key, spec in schema.items():
        dotted = f"{prefix}.{key}" if prefix else key
        if isinstance(spec, dict):
            out.update(schema_defaults(spec, dotted))
        elif spec.default is not REQUIRED:
            out[dotted] = spec.default
    return out


def typed_table(cls_name: str, schema: dict, module: str, doc: str = "") -> type:
    """A frozen dataclass for one table: one attribute per field, named by its SI name.

    Assign it to the name ``cls_name`` in ``module`` (pickle finds it there:
    tables travel to dask workers).
    """
    fields = [(f.si_name(k), Any) for k, f in schema.items() if isinstance(f, Field)]
    names = [n for n, _ in fields]
    if len(set(names)) != len(names):
        raise AssertionError(f"{cls_name}: SI names collide: {names}")  # schema bug
    cls = make_dataclass(cls_name, fields, frozen=True)
    cls.__doc__ = doc or f"The validated ``{cls_name}`` table (SI values, SI names)."
    cls.__module__ = module
    return cls


def to_typed(cls: type, values: dict, schema: dict):
    """An instance of ``cls`` (:func:`typed_table`) from :func:`validate`'s output."""
    return cls(**{f.si_name(k): values[k] for k, f in schema.items() if isinstance(f, Field)})


class LiveTable(dict):
    """A table schema rebuilt from a registry on every read (``build() -> {key: Field}``).

    A table whose keys are declared by registry entries (the ``[monte_carlo]``
    keys by the dispersions) stays a ``dict`` for :func:`validate`, yet follows
    entries registered after import.
    """

    def __init__(self, build):
        super().__init__()
        self._build = build

    def _now(self) -> dict:
        return self._build()

    def __iter__(self):
        return iter(self._now())

    def __contains__(self, key) -> bool:
        return key in self._now()

    def __getitem__(self, key):
        return self._now()[key]

    def __len__(self) -> int:
        return len(self._now())

    def keys(self):
        return self._now().keys()

    def items(self):
        return self._now().items()

    def values(self):
        return self._now().values()

    def get(self, key, default=None):
        return self._now().get(key, default)


def live_typed_table(cls: type, schema: dict, module: str) -> type:
    """``cls`` (:func:`typed_table` of ``schema`` at import) while the live ``schema``
    has the same fields; else a fresh table class with the registered fields."""
    names = tuple(f.si_name(k) for k, f in schema.items() if isinstance(f, Field))
    if names == tuple(f.name for f in dc_fields(cls)):
        return cls
    return typed_table(cls.__name__, dict(schema.items()), module)
