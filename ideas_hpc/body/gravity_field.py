"""Loader for spherical-harmonic gravity fields (PDS ``n15acoeff.tab`` + ``.lbl``).

Table rows (PDS NEAR-A-5-COLLECTED-MODELS ``N15ACOEFF.TAB``)::

    degree  order  C_nm  S_nm  [sigma_C  sigma_S]

with *fully normalised* coefficients. The reference radius and GM are not in
the table: they are read from the PDS label's DESCRIPTION text::

    Reference Radius:  16.0km
    Gravitational Constant, GM:   4.46275472004E-04 km^3/s^2

A table may instead start with a SHADR-style header line
``R_ref_km, GM_km3_s2, sigma_GM, degree, order, normalised(1/0)[, ...]``
(comma separated); then no label is needed. Units are converted to SI here,
once (km -> m, km^3/s^2 -> m^3/s^2).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ideas_hpc.body.datapath import find_data_file
from ideas_hpc.base.errors import InputError

KM = 1000.0
MAX_DEGREE = 60  # unnormalised solid harmonics (core.gravity) overflow near degree 80

_RE_RREF = re.compile(r"Reference\s+Radius\s*:\s*([0-9.+\-EeDd]+)\s*(km|m)\b", re.I)
_RE_GM = re.compile(r"GM\s*:\s*([0-9.+\-EeDd]+)\s*(km\^3/s\^2|m\^3/s\^2)", re.I)
_RE_NORM = re.compile(r"Coefficients\s+Normali[sz]ed\s*:\s*(\w+)", re.I)


@dataclass(frozen=True)
class SHField:
    """A spherical-harmonic gravity field (SI).

    Attributes
    ----------
    name : str
    source : str
        Table path (and label path).
    degree : int
        Highest degree in the table.
    r_ref : float
        Reference radius, m.
    gm : float
        m^3/s^2.
    cbar, sbar : (degree+1, degree+1) float64
        Fully normalised coefficients ``[n, m]``; ``cbar[0, 0] = 1``.
    """

    name: str
    source: str
    degree: int
    r_ref: float
    gm: float
    cbar: np.ndarray = field(repr=False)
    sbar: np.ndarray = field(repr=False)

    def truncated(self, degree: int) -> "SHField":
        """The field up to ``degree`` (``<= self.degree``)."""
        d = int(degree)
        return SHField(self.name, self.source, d, self.r_ref, self.gm,
                       np.ascontiguousarray(self.cbar[:d + 1, :d + 1]),
                       np.ascontiguousarray(self.sbar[:d + 1, :d + 1]))


def _float(tok: str) -> float:
    return float(tok.replace("D", "E").replace("d", "e"))


def _find_label(tab: Path) -> Path | None:
    for cand in (tab.with_suffix(".lbl"), tab.with_suffix(".LBL")):
        if cand.is_file():
            return cand
    low = tab.stem.lower()
    for p in tab.parent.iterdir():
        if p.suffix.lower() == ".lbl" and p.stem.lower() == low:
            return p
    return None


def _parse_label(lbl: Path) -> tuple[float, float]:
    text = lbl.read_text(errors="replace")
    m = _RE_RREF.search(text)
    if m is None:
        raise InputError("label has no 'Reference Radius: <value> km' in its DESCRIPTION",
                         field="r_ref", file=lbl)
    try:
        r_ref = _float(m.group(1)) * (KM if m.group(2).lower() == "km" else 1.0)
    except ValueError:
        raise InputError(f"bad reference radius {m.group(1)!r}", field="r_ref", file=lbl,
                         line=text[:m.start()].count("\n") + 1) from None
    g = _RE_GM.search(text)
    if g is None:
        raise InputError("label has no 'GM: <value> km^3/s^2' in its DESCRIPTION",
                         field="gm", file=lbl)
    try:
        gm = _float(g.group(1)) * (KM ** 3 if g.group(2).lower().startswith("km") else 1.0)
    except ValueError:
        raise InputError(f"bad GM {g.group(1)!r}", field="gm", file=lbl,
                         line=text[:g.start()].count("\n") + 1) from None
    nm = _RE_NORM.search(text)
    if nm is not None and nm.group(1).lower() not in ("yes", "true", "1"):
        raise InputError("only fully normalised coefficients are supported "
                         f"(label says 'Coefficients Normalized: {nm.group(1)}')",
                         field="normalized", file=lbl, line=text[:nm.start()].count("\n") + 1)
    for name, val in (("r_ref", r_ref), ("gm", gm)):
        if not (math.isfinite(val) and val > 0):
            raise InputError(f"must be finite and > 0, got {val!r}", field=name, file=lbl)
    return r_ref, gm


def _parse_header(line: str, path: Path) -> tuple[float, float]:
    toks = [t.strip() for t in line.replace(",", " ").split()]
    try:
        vals = [_float(t) for t in toks]
    except ValueError:
        raise InputError(f"bad header {line.strip()!r}: expected 'R_ref_km, GM_km3_s2, "
                         "sigma_GM, degree, order, normalised, ...'", field="header",
                         file=path, line=1) from None
    if len(vals) < 6:
        raise InputError(f"bad header {line.strip()!r}: need at least 6 values (R_ref_km, "
                         "GM_km3_s2, sigma_GM, degree, order, normalised)", field="header",
                         file=path, line=1)
    r_ref, gm = vals[0] * KM, vals[1] * KM ** 3
    if not (math.isfinite(r_ref) and r_ref > 0 and math.isfinite(gm) and gm > 0):
        raise InputError(f"bad header {line.strip()!r}: R_ref and GM must be > 0",
                         field="header", file=path, line=1)
    if vals[5] != 1:
        raise InputError("bad header: only normalised coefficients (flag 1) are supported",
                         field="header", file=path, line=1)
    return r_ref, gm


def _is_row(line: str) -> bool:
    toks = line.split()
    return len(toks) >= 4 and toks[0].lstrip("+-").isdigit() and toks[1].lstrip("+-").isdigit()


def load_sh_field(name_or_path="n15acoeff.tab", *, data_path=None) -> SHField:
    """Read a normalised spherical-harmonic table and its label.

    Parameters
    ----------
    name_or_path : str or path-like
        A file name searched on the data path (``n15acoeff.tab``) or a path.
    data_path : path-like, optional
        Searched before ``IDEAS_HPC_DATA``.

    Raises
    ------
    InputError
        Naming the file and line: missing label, label without reference
        radius or GM, bad header line, bad row (not ``n m C S``, ``m > n``,
        non-finite value, duplicate), degree above :data:`MAX_DEGREE`.
    """
    p = Path(str(name_or_path)).expanduser()
    if not p.is_file():
        if "/" in str(name_or_path) or "\\" in str(name_or_path):
            raise InputError(f"gravity field file not found: {p}", field="sh_file", file=p)
        p = find_data_file(str(name_or_path), data_path)
    lines = p.read_text(errors="replace").splitlines()
    first = next((i for i, ln in enumerate(lines) if ln.strip()), None)
    if first is None:
        raise InputError("empty gravity field table", field="sh_file", file=p)
    source = str(p)
    if _is_row(lines[first]):
        lbl = _find_label(p)
        if lbl is None:
            raise InputError(f"no PDS label ({p.stem}.lbl) beside the table and no header line; "
                             "the reference radius and GM come from the label",
                             field="label", file=p)
        r_ref, gm = _parse_label(lbl)
        source += f" (label {lbl})"
        start = first
    else:
        if first != 0:
            raise InputError("bad header: leading blank lines", field="header", file=p, line=1)
        r_ref, gm = _parse_header(lines[0], p)
        start = 1
    rows = []
    for i in range(start, len(lines)):
        ln = lines[i]
        if not ln.strip():
            continue
        toks = ln.replace(",", " ").split()
        try:
            n, m = int(toks[0]), int(toks[1])
            c, s = _float(toks[2]), _float(toks[3])
        except (ValueError, IndexError):
            raise InputError(f"bad row {ln.strip()!r}: expected 'degree order C S ...'",
                             field="row", file=p, line=i + 1) from None
        if n < 0 or m < 0 or m > n:
            raise InputError(f"bad row: need 0 <= order <= degree, got degree {n} order {m}",
                             field="row", file=p, line=i + 1)
        if not (math.isfinite(c) and math.isfinite(s)):
            raise InputError("bad row: non-finite coefficient", field="row", file=p, line=i + 1)
        if n > MAX_DEGREE:
            raise InputError(f"degree {n} above the supported {MAX_DEGREE}", field="row",
                             file=p, line=i + 1)
        rows.append((n, m, c, s, i + 1))
    if not rows:
        raise InputError("no coefficient rows", field="row", file=p)
    deg = max(r[0] for r in rows)
    cbar = np.zeros((deg + 1, deg + 1))
    sbar = np.zeros((deg + 1, deg + 1))
    seen = {}
    for n, m, c, s, ln in rows:
        if (n, m) in seen:
            raise InputError(f"duplicate degree {n} order {m} (first on line {seen[(n, m)]})",
                             field="row", file=p, line=ln)
        seen[(n, m)] = ln
        cbar[n, m] = c
        sbar[n, m] = s
    if (0, 0) not in seen:
        cbar[0, 0] = 1.0
    return SHField(p.stem.lower(), source, deg, r_ref, gm, cbar, sbar)


def sh_from_degree2(c20_m2: float, c22_m2: float, r_ref: float, gm: float) -> SHField:
    """A degree-2 field ``C00 = 1, C20, C22`` (SPEC section 4 units) as a normalised table.

    ``Cbar_20 = c20 / (R^2 sqrt(5))``, ``Cbar_22 = c22 / (R^2 sqrt(5/12))``
    (Kaula normalisation ``N_nm = sqrt((2 - delta_m0)(2n+1)(n-m)!/(n+m)!)``).
    """
    cbar = np.zeros((3, 3))
    sbar = np.zeros((3, 3))
    cbar[0, 0] = 1.0
    cbar[2, 0] = c20_m2 / r_ref ** 2 / math.sqrt(5.0)
    cbar[2, 2] = c22_m2 / r_ref ** 2 / math.sqrt(5.0 / 12.0)
    return SHField("degree2", "built from C20, C22", 2, float(r_ref), float(gm), cbar, sbar)
