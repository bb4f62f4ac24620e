"""The coverage requirement as one record (issue 40): the percentage converted once, the
target rule and ``need`` computed in one function, one comparison, one area row.

Oracles: exact rational arithmetic (:mod:`fractions`) for the conversion, the rule's
definition written out for the threshold, and the package's own source (AST) for the
"in one place" claims, each with a check that it sees a violation.
"""

from __future__ import annotations

import ast
import math
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from ideas_hpc.base.errors import InputError
from ideas_hpc.campaign.schema.campaign_tables import load, resolved_config
from ideas_hpc.campaign.schema.design_table import DESIGN
from ideas_hpc.campaign.setup import requirement_from_campaign
from ideas_hpc.mapping.options import CoverageOptions
from ideas_hpc.mapping.requirement import COVER_TOL, Requirement, meets, threshold_of

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "ideas_hpc"
NOMINAL = ROOT / "campaigns" / "eros-design-nominal.toml"


def test_the_percentage_converts_to_the_correctly_rounded_fraction():
    """x % is x / 100 rounded once (what the code that divided by 100 computed), for every
    value: multiplying by 0.01 instead differs in the last bit for about one in eight."""
    f = DESIGN["eps_tol_pct"]
    rng = np.random.default_rng(0)
    values = [round(x, int(d)) for x, d in zip(rng.uniform(0.0, 100.0, 2000),
                                               rng.integers(1, 5, 2000))]
    assert any(x * 0.01 != float(Fraction(x) / 100) for x in values)   # the trap is real
    for x in values:
        assert f.convert(float(x)) == float(Fraction(float(x)) / 100)


def test_the_campaign_holds_the_fraction_and_stores_the_file_key():
    """The typed table holds ``eps_tol`` (fraction); a store records the file's key and value,
    so config hashes and ``--resume`` of stores written before are unchanged."""
    c = load(NOMINAL, ["design.eps_tol_pct=0.7"])
    assert c.config.design.eps_tol == float(Fraction(0.7) / 100)   # of the float 0.7
    assert not hasattr(c.config.design, "eps_tol_pct")
    rc = resolved_config(c)
    assert rc["design"]["eps_tol_pct"] == 0.7 and "eps_tol" not in rc["design"]
    r = requirement_from_campaign(c)
    assert r.eps_tol == c.config.design.eps_tol and r.limits is c.extras["coverage"]
    assert r.rule == "reach" and r.reference == "surface"


@pytest.mark.parametrize("reach", [0.2, 0.98, 0.99, 0.99 + 1e-12, 0.995, 1.0, None])
def test_the_reach_rule_is_one_or_the_reach(reach):
    """SPEC's rule: the target is 100 %, or what the candidates reach together when that is
    below 100 % - eps_tol; the threshold is target - eps_tol."""
    eps = 0.01
    thr = Requirement(eps_tol=eps).threshold(reach)
    want = reach if reach is not None and reach < 1.0 - eps else 1.0
    assert thr.target == want and thr.need == want - eps and thr.eps_tol == eps
    assert thr.reach == reach


def test_the_full_rule_refuses_an_unreachable_target():
    r = Requirement(eps_tol=0.01, rule="full")
    assert r.threshold(0.995).target == 1.0
    with pytest.raises(InputError) as ei:
        r.threshold(0.95)
    assert ei.value.field == "rule" and "95.000 %" in ei.value.message


def test_meets_keeps_the_evaluators_tolerance():
    need = 0.99
    assert COVER_TOL == 1e-12
    cov = np.array([need, need - 0.5e-12, need - 2e-12, need + 1e-15])
    np.testing.assert_array_equal(meets(cov, need), [True, True, False, True])
    assert threshold_of(1.0, 0.01).meets(0.99 - 0.5e-12)


@pytest.mark.parametrize("bad", [
    dict(eps_tol=-0.1), dict(eps_tol=1.5), dict(eps_tol=math.nan),
    dict(eps_tol=0.01, rule="most"), dict(eps_tol=0.01, reference="lit-ish")])
def test_a_bad_requirement_names_its_parameter(bad):
    with pytest.raises(InputError) as ei:
        Requirement(**bad)
    assert ei.value.field == next(k for k in ("rule", "reference", "eps_tol") if k in bad)


def test_the_settings_take_the_threshold_or_the_older_keywords():
    from ideas_hpc.design.settings import CoverSettings, ReliableSettings

    thr = Requirement(eps_tol=0.02, limits=CoverageOptions()).threshold(0.9)
    a, b = CoverSettings(threshold=thr, n_max=3), CoverSettings(target=0.9, eps_tol=0.02, n_max=3)
    assert (a.target, a.eps_tol, a.threshold.need) == (0.9, 0.02, b.threshold.need)
    with pytest.raises(InputError):
        CoverSettings(threshold=thr, target=1.0, n_max=3)
    assert ReliableSettings(p=0.9, p_f=0.05, threshold=thr, n_max=4).need == thr.need
    assert ReliableSettings(p=0.9, p_f=0.05, need=0.8, n_max=4).need == 0.8


# -- "in one place": the package's own source --------------------------------------------

def _names(node) -> set[str]:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)} | \
        {n.attr for n in ast.walk(node) if isinstance(n, ast.Attribute)}


def _violations(tree) -> list[tuple[int, str]]:
    """Lines that convert eps_tol_pct, compute a target minus eps, add FEAS_TOL to a
    need, or compare a coverage with a need minus a literal tolerance."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr == "eps_tol_pct":
            out.append((node.lineno, "reads eps_tol_pct (convert it in its Field)"))
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Sub):
            left, right = _names(node.left), _names(node.right)
            if any("eps" in n for n in right) and (
                    any("target" in n or "reach" in n or n == "ring" for n in left)
                    or isinstance(node.left, ast.Constant)):
                out.append((node.lineno, "target - eps_tol (threshold_of)"))
            if any("need" in n or "threshold" in n for n in left) and \
                    isinstance(node.right, ast.Constant) and node.right.value == 1e-12:
                out.append((node.lineno, "need - 1e-12 (meets)"))
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Add) and \
                "FEAS_TOL" in _names(node) and \
                any("need" in n or "threshold" in n for n in _names(node)):
            out.append((node.lineno, "need + FEAS_TOL (design/area.py)"))
    return out


#: The modules that do these things, once.
HOMES = {"mapping/requirement.py", "design/area.py"}


def test_the_requirement_is_computed_in_one_place():
    hits = []
    for f in sorted(PACKAGE.rglob("*.py")):
        rel = f.relative_to(PACKAGE).as_posix()
        if rel in HOMES:
            continue
        hits += [f"{rel}:{line} {what}" for line, what in
                 _violations(ast.parse(f.read_text(), str(f)))]
    assert not hits, "the requirement computed outside its home:\n" + "\n".join(hits)


@pytest.mark.parametrize("code", [
    "eps = d.eps_tol_pct / 100.0", "need = target - eps_tol", "t = 1.0 if r >= 1.0 - eps else r",
    "ok = cov >= need - 1e-12", "row = LinearConstraint(w, need + FEAS_TOL, inf)",
    "n = greedy(rows, ring - eps)"])
def test_the_source_check_sees_each_violation(code):
    assert _violations(ast.parse(code))
