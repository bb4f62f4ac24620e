"""Small inputs a new user meets (issue 33): a byte-order mark, a percentage where a
fraction is asked, ``--resume`` onto a store of another kind."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ideas_hpc.campaign.schema.campaign_tables import load, resolved_config
from ideas_hpc.engine.store import config_problems
from ideas_hpc.engine.store_meta import config_hash
from ideas_hpc.base.errors import InputError

CAMPAIGNS = Path(__file__).resolve().parent.parent / "campaigns"


def test_a_utf8_byte_order_mark_is_accepted(tmp_path):
    text = (CAMPAIGNS / "eros-flyby.toml").read_text(encoding="utf-8")
    plain, bom = tmp_path / "plain.toml", tmp_path / "bom.toml"
    plain.write_text(text, encoding="utf-8")
    bom.write_bytes(b"\xef\xbb\xbf" + text.encode("utf-8"))
    assert resolved_config(load(bom)) == resolved_config(load(plain))


def test_a_percentage_for_a_fraction_says_it_is_a_fraction():
    with pytest.raises(InputError) as exc:
        load(CAMPAIGNS / "eros-design.toml", ["design.success_probability=90"])
    msg = str(exc.value)
    assert "design.success_probability" in msg and "a fraction, e.g. 0.9" in msg


def test_a_value_out_of_range_that_is_no_percentage_gets_no_fraction_hint():
    with pytest.raises(InputError) as exc:
        load(CAMPAIGNS / "eros-design.toml", ["design.success_probability=-0.5"])
    assert "fraction" not in str(exc.value)


def test_resume_onto_another_kind_names_the_kind_first():
    stored = resolved_config(load(CAMPAIGNS / "eros-monte-carlo.toml"))
    now = resolved_config(load(CAMPAIGNS / "eros-flyby.toml"))
    attrs = {"config": stored, "config_hash": config_hash(stored), "campaign_seed": 2026}
    problems = config_problems(attrs, now, 2026)
    assert problems[0] == "a store of kind 'monte-carlo', this campaign is kind 'flyby'"
    assert not any(p.startswith("kind =") for p in problems[1:])


def test_resume_onto_the_same_kind_lists_only_the_differences():
    stored = resolved_config(load(CAMPAIGNS / "eros-flyby.toml"))
    now = resolved_config(load(CAMPAIGNS / "eros-flyby.toml", ["flyby.tf_s=300"]))
    attrs = {"config": stored, "config_hash": config_hash(stored), "campaign_seed": 2026}
    problems = config_problems(attrs, now, 2026)
    assert problems and not any("kind" in p for p in problems)
    assert any(p.startswith("flyby.tf_s") for p in problems)


def test_scan_arrival_says_when_lighting_is_off(tmp_path, capsys):
    """Without a lighting requirement every epoch maps the same: the scan says so and
    names the key to set, instead of crowning the first of equals."""
    from ideas_hpc.campaign.scan import scan_file

    sets = ['body.name="ellipsoid"', "flyby.tf_s=60", "flyby.z_start_km=-3",
            "flyby.z_stop_km=3"]
    ds = scan_file(CAMPAIGNS / "eros-flyby.toml", sets, n=2, span_h=1.0)
    printed = capsys.readouterr().out
    assert float(np.ptp(ds["coverage"].values)) == 0.0
    assert "coverage.require_lit" in printed and "lighting is off" in printed
    assert "best arrival epoch: none, every epoch maps the same coverage" in printed


def test_a_percentage_for_a_confidence_says_it_is_a_fraction():
    with pytest.raises(InputError) as exc:
        load(CAMPAIGNS / "eros-design.toml", ["design.confidence=95"])
    assert "design.confidence" in str(exc.value) and "a fraction, e.g. 0.9" in str(exc.value)
