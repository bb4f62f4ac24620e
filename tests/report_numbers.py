"""Find numbers in a report's ``summary.txt`` by what they measure, not by its wording.

A value is *printed* when a line mentioning one of its keywords (a regex,
case-insensitive) carries a number equal to it within that number's printed
precision (half a unit of its last digit). Labels may be reworded freely; a
wrong or missing number fails.
"""

from __future__ import annotations

import math
import re

NUMBER = re.compile(r"(?<![\w.])[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


def _close(token: str, value: float) -> bool:
    mant, _, exp = token.lower().partition("e")
    dec = len(mant.split(".")[1]) if "." in mant else 0
    half = 0.5 * 10.0 ** (-dec + (int(exp) if exp else 0))
    return abs(float(token) - value) <= half * (1 + 1e-9) + 1e-12 * abs(value)


def _match(toks: list[str], values) -> bool:
    """Every value matched by a number of its own (equal values need as many numbers)."""
    free = list(toks)
    for v in sorted(values, key=lambda v: sum(_close(t, v) for t in toks)):
        hit = next((t for t in free if _close(t, v)), None)
        if hit is None:
            return False
        free.remove(hit)
    return True


def lines_for(text: str, key: str) -> list[str]:
    out = [ln for ln in text.splitlines() if re.search(key, ln, re.I)]
    assert out, f"no line of the summary mentions {key!r}:\n{text}"
    return out


def printed(text: str, key: str, *values: float, decimals: int | None = None) -> None:
    """Some one line mentioning ``key`` prints every value of ``values``, each as a
    number of its own.

    ``decimals``: the least number of decimals a matching number must have
    (so that 99.781 is not matched by a printed 100).
    """
    lines = lines_for(text, key)
    for ln in lines:
        toks = [t for t in NUMBER.findall(ln)
                if decimals is None or ("." in t and len(t.split(".")[1]) >= decimals)]
        if _match(toks, values):
            return
    raise AssertionError(f"{values} not printed on one line mentioning {key!r}:\n"
                         + "\n".join(lines))


def printed_int(text: str, key: str, *values: int) -> None:
    """Some one line mentioning ``key`` prints every integer of ``values`` exactly."""
    lines = lines_for(text, key)
    for ln in lines:
        toks = {t for t in NUMBER.findall(ln) if "." not in t and "e" not in t.lower()}
        if all(str(int(v)) in toks for v in values):
            return
    raise AssertionError(f"{values} not printed on one line mentioning {key!r}:\n"
                         + "\n".join(lines))


def sig(value: float, digits: int) -> float:
    """``value`` rounded to ``digits`` significant digits (what ``%.{digits}g`` prints)."""
    if value == 0 or not math.isfinite(value):
        return value
    return round(value, digits - 1 - int(math.floor(math.log10(abs(value)))))
