"""``ideas-hpc study --ca-distances-km``: the closest-approach distance from a short list
(issue 42 deliverable 5; :mod:`ideas_hpc.campaign.study_distance`).

Oracles: the store's own distance rebuilt through ``flyby.d_sep_km`` is the design's own
setup, bank and answer (the same N and P exactly); another distance's row is the fewest N
of a bank built from the setup with only ``d_sep_m`` set to it (the field, directly); the
sizing's definition ``h = x D / lambda`` makes the GSD at its own ring radius the
instrument's ground resolution, and the pass's closed forms give ``omega_0 d = v``.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from ideas_hpc.base.errors import InputError
from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.campaign.study import Study, StudyOptions
from ideas_hpc.campaign.study_distance import (OPTION, camera_figures, camera_ifov_rad,
                                               distance_setup, distance_value, parse_km)

ROOT = Path(__file__).resolve().parent.parent
CAMPAIGN = ROOT / "campaigns" / "eros-class-flyby.toml"
SMALL = ["design.angle_step_deg=20", "design.n_max=6", "design.time_limit_s=20"]
SWARM = np.deg2rad([0.0, 120.0, 240.0])     # on the 20 deg grid


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    c = load(CAMPAIGN, SMALL)
    return Study(store=tmp_path_factory.mktemp("dist") / "s.zarr", c=c,
                 setup=setup_from_campaign(c), theta=SWARM, need=0.99,
                 p=float(c.config.design.success_probability))


def test_own_distance_is_the_design_and_others_apply_their_distance(study):
    """The own distance rebuilt through ``flyby.d_sep_km`` gives the design's N, P and the
    swarm's P exactly (own row of the answer too); the 100 km row is the search on a bank of
    the setup with ``d_sep_m = 100 km`` set directly, and differs from the own row."""
    own = float(study.setup.d_sep_m)
    design = study.fewest(study.setup, study.bank(study.setup, None))
    rebuilt = distance_setup(study.c, own)
    assert rebuilt.d_sep_m == own
    again = study.fewest(rebuilt, study.bank(rebuilt, "oracle-own"))
    assert again == design and design["n"] > 0
    ds = distance_value(study, (100e3,))
    d = ds["ca_distance"].values
    np.testing.assert_array_equal(d, [100e3, own])
    i = 1
    assert int(ds["fewest_n"].values[i]) == design["n"]
    assert float(ds["fewest_probability"].values[i]) == design["probability"]
    assert float(ds["swarm_probability"].values[i]) == design["swarm_probability"]
    direct = dataclasses.replace(study.setup, d_sep_m=100e3)
    ref = study.fewest(direct, study.bank(direct, "oracle-100km"))
    assert int(ds["fewest_n"].values[0]) == ref["n"]
    assert float(ds["swarm_probability"].values[0]) == ref["swarm_probability"]
    assert ref["swarm_probability"] != design["swarm_probability"]
    np.testing.assert_equal(float(ds["fewest_probability"].values[0]), ref["probability"])
    best = int(ds.attrs["best"])
    n, p = ds["fewest_n"].values, ds["fewest_probability"].values
    ok = [j for j in range(n.size) if n[j] > 0]
    assert best == min(ok, key=lambda j: (n[j], -p[j]))


@pytest.mark.parametrize("text", ["", " , ", "0,100", "100,-5", "a,b", "100,nan", "inf"])
def test_a_bad_list_is_one_input_error_naming_the_option(text):
    with pytest.raises(InputError) as exc:
        parse_km(text)
    assert exc.value.field == OPTION and "\n" not in str(exc.value)


def test_the_distance_answer_without_a_list_is_refused():
    with pytest.raises(InputError) as exc:
        StudyOptions(answers=("distance",), distances_m=())
    assert exc.value.field == OPTION
    with pytest.raises(InputError) as exc:
        StudyOptions(answers=("distance",), distances_m=("x",))
    assert exc.value.field == OPTION


def test_gsd_is_the_sizings_at_its_radius_and_the_los_rate_is_v_over_d(study):
    """At the sizing's own ring radius the GSD is the instrument's ground resolution
    (``h = x D / lambda``, :func:`~ideas_hpc.flyby.sizing.size_flyby`); the GSD grows as
    ``(d - R_av) IFOV`` (linear in d) and the peak LOS rate is ``v / d``
    (:mod:`ideas_hpc.flyby.pass_rates`); the pointing bias is ``sigma_B / d``."""
    s = study.setup
    inst = study.c.config.instrument
    ifov = camera_ifov_rad(study.c, s)
    d = np.array([0.5, 1.0, 2.0, 3.0]) * s.sizing.d_sep
    f = camera_figures(s, d, ifov)
    at_own = camera_figures(s, [s.sizing.d_sep], ifov)["gsd_m"][0]
    np.testing.assert_allclose(at_own, inst.ground_resolution_m, rtol=1e-12)
    slope = np.diff(f["gsd_m"]) / np.diff(d)
    np.testing.assert_allclose(slope, inst.wavelength_m / inst.aperture_m, rtol=1e-12)
    np.testing.assert_allclose(f["los_rate_rad_s"] * d, s.encounter.speed_m_s, rtol=1e-12)
    np.testing.assert_allclose(f["pointing_bias_rad"] * d, s.navigation.error.sigma_major_m,
                               rtol=1e-12)
