"""The judgement of a loaded campaign's keys against what its run reads (issue 41):
:func:`check_reads` refuses a key the run ignores, except a file key that a ``--set``
override switched off (:func:`switched_off`), which is warned about in one line. The
declarations themselves are :mod:`ideas_hpc.campaign.schema.reads`."""

from __future__ import annotations

from ideas_hpc.base.errors import InputError
from ideas_hpc.campaign.schema.read_settings import Settings, set_keys
from ideas_hpc.campaign.schema.reads import is_read, rule_of


def check_reads(config, raw: dict, schema: dict, switched_off=None) -> list:
    """Refuse the first key ``raw`` sets that the campaign ``config`` does not read (one
    :class:`InputError` naming the key; the caller adds the file and line).

    ``switched_off(key) -> bool`` (optional) says that the key is the file's own and the
    file alone reads it: a ``--set`` override switched it off (``--set
    attitude.mode="ideal"`` on a file with a ``[controller]``). Such a key is not refused
    but returned, ``[(key, why), ...]``, for the caller to warn about in one line each:
    nothing is silent, and turning a setting off from the command line still runs.
    """
    s = Settings(config, raw)
    off = []
    for key in set_keys(raw, schema):
        rule = rule_of(key)
        if not rule.when(s):
            if switched_off is not None and switched_off(key):
                off.append((key, rule.why(s)))
                continue
            raise InputError(rule.why(s), field=key)
    return off


def switched_off(source, schema: dict, load_source, typed):
    """``key -> bool`` for :func:`check_reads`: the file sets ``key`` itself (no ``--set`` of
    it) and the file without its overrides reads it, so an override switched it off.
    ``load_source(path)`` loads the file without overrides, ``typed(data)`` validates it
    into a typed config; None without overrides."""
    if not source.overrides or source.path is None:
        return None
    given = {ov.split("=", 1)[0].strip() for ov in source.overrides}
    memo: dict = {}

    def file_reads(key: str) -> bool:
        if key in given or source.where(key)[0] == "--set":
            return False
        if "settings" not in memo:
            try:
                bare = load_source(source.path)
                memo["settings"] = Settings(typed(bare.data), bare.data)
            except InputError:
                memo["settings"] = None
        return memo["settings"] is not None and is_read(key, memo["settings"])
    return file_reads
