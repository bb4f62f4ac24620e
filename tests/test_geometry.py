"""The flyby geometry as an object (issue 30): the paper's and an encounter's are two
implementations of one interface, chosen once from the setup; checked against the
geometry each one states (SPEC section 3 ring, SPEC 7c encounter ring)."""

from __future__ import annotations

import numpy as np

from ideas_hpc.campaign.schema.campaign_tables import load
from ideas_hpc.campaign.setup import setup_from_campaign
from ideas_hpc.flyby.flight import endpoints
from ideas_hpc.flyby.geometry import PAPER, EncounterGeometry, Geometry, PaperGeometry

TOML = """
kind = "flyby"
[body]
name = "sphere"
resolution = 2
[flyby]
{flyby}
[dynamics]
gravity = "point_mass"
srp = false
[swarm]
angles_rad = [0.0, 2.0, 4.0]
"""

THETA = np.array([0.0, 2.0, 4.0])


def _setup(tmp_path, flyby: str):
    p = tmp_path / "g.toml"
    p.write_text(TOML.format(flyby=flyby))
    return setup_from_campaign(load(p))


def test_paper_geometry_starts_and_ends_on_its_ring(tmp_path):
    s = _setup(tmp_path, "")
    assert s.geometry is PAPER and isinstance(s.geometry, PaperGeometry)
    r0, rt = endpoints(s, THETA)
    ring = s.d_sep_m * np.stack([np.cos(THETA), np.sin(THETA)], axis=1)
    np.testing.assert_allclose(r0[:, :2], ring, atol=1e-6)
    np.testing.assert_allclose(rt[:, :2], ring, atol=1e-6)
    np.testing.assert_allclose(r0[:, 2], s.z_start_m)
    np.testing.assert_allclose(rt[:, 2], s.z_stop_m)
    assert s.geometry.attrs(s) == {"geometry": "paper"}
    spin, dcm_TS = s.geometry.maneuver_frame(s, 1.5e-4)
    assert spin == 1.5e-4 and dcm_TS is None   # the rings turn with the body


def test_encounter_ring_is_normal_to_the_approach_at_closest_approach(tmp_path):
    s = _setup(tmp_path, 'geometry = "encounter"\napproach_ra_deg = 30.0\napproach_dec_deg = 20.0')
    geo = s.geometry
    assert isinstance(geo, EncounterGeometry) and geo.encounter == s.encounter
    _, r_ca = endpoints(s, THETA)
    u = s.encounter.v_inf_T / np.linalg.norm(s.encounter.v_inf_T)
    np.testing.assert_allclose(np.linalg.norm(r_ca, axis=1), s.d_sep_m, rtol=1e-9)
    np.testing.assert_allclose(r_ca @ u, 0.0, atol=1e-6 * s.d_sep_m)
    spin, dcm_TS = geo.maneuver_frame(s, 1.5e-4)
    assert spin == 0.0                            # the rings are fixed in N
    np.testing.assert_allclose(dcm_TS, s.encounter.dcm_NS)
    assert geo.attrs(s)["geometry"] == "encounter"


def test_every_geometry_implements_the_whole_interface():
    methods = [m for m in vars(Geometry) if not m.startswith("_") and callable(vars(Geometry)[m])
               and m != "camera"]
    for cls in (PaperGeometry, EncounterGeometry):
        for m in methods:
            assert getattr(cls, m) is not getattr(Geometry, m), f"{cls.__name__}.{m}"
