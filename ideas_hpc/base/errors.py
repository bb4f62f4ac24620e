"""Exceptions raised by the boundary layer.

Every bad-input error says *where*: the field name, and when the input came
from a file, the file and line. The CLI prints ``str(exc)`` on one line and
exits with status 2, without a traceback.
"""

from __future__ import annotations

import contextlib
import math
import re


class InputError(ValueError):
    """Bad user input: a config field, a data file line, a function argument.

    Parameters
    ----------
    message : str
        What is wrong, in plain words.
    field : str, optional
        Dotted name of the offending field or argument (``swarm.n_max``).
    file : str, optional
        File the value came from.
    line : int, optional
        1-based line in ``file``.
    """

    def __init__(self, message: str, *, field: str | None = None,
                 file: str | None = None, line: int | None = None):
        self.message = message
        self.field = field
        self.file = str(file) if file is not None else None
        self.line = line
        super().__init__(self._format())

    def _format(self) -> str:
        where = ""
        if self.file is not None:
            where = self.file + (f":{self.line}" if self.line is not None else "")
        parts = []
        if where:
            parts.append(where)
        if self.field:
            parts.append(self.field)
        prefix = ": ".join(parts)
        return f"{prefix}: {self.message}" if prefix else self.message


class DataNotFoundError(InputError, FileNotFoundError):
    """A named data set (shape model, gravity field) was not found on the data path."""


@contextlib.contextmanager
def config_fields(names: dict | None = None, prefix: str = ""):
    """Re-raise a model's or designer's :class:`InputError` under the file's keys.

    The layer below names its own parameters (``p_min``, ``sh_degree``), in the
    field and, between backticks, in the message (``"raise `n_max`"``); the
    campaign layer maps them: ``names[name]`` when listed, else ``prefix + name``
    (a name the mapping does not cover keeps its own spelling, without the
    backticks, in the message).
    """
    try:
        yield
    except InputError as e:
        def mapped(name):
            if names and name in names:
                return names[name]
            return prefix + name if prefix else None

        key = mapped(e.field) if e.field is not None else None
        message = _PARAM.sub(lambda m: mapped(m.group(1)) or m.group(1), e.message)
        if key is None and message == e.message:
            raise
        raise InputError(message, field=key or e.field, file=e.file, line=e.line) from None


#: A parameter name quoted in a model's message, mapped by :func:`config_fields`.
_PARAM = re.compile(r"`([A-Za-z_][A-Za-z0-9_]*)`")
