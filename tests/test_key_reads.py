"""No key is silently ignored by any kind (issue 41): every kind is loaded with every key.

For each kind (and each ``design.method`` entry, the success-probability design, a
simulated attitude and an encounter) a minimal campaign is loaded with each key of
the schema set to a valid value other than its default. The load either succeeds,
and the declaration (:mod:`ideas_hpc.campaign.schema.reads`) says the run reads the
key, or it is refused with one :class:`InputError` naming the key. The only other
refusal allowed names a key the variant itself sets which the new key switches off
(``design.nadir_store`` replaces ``swarm.angles_rad``): then the new key is read and
the other one, read before, is not. Loading only, no runs (tests/test_key_reads_runs.py
checks the declaration against what real runs read).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from ideas_hpc.base.errors import InputError
from ideas_hpc.base.fields import Field
from ideas_hpc.campaign.schema import reads
from ideas_hpc.campaign.schema.campaign_tables import SCHEMA, load, resolved_config, validate_campaign
from ideas_hpc.campaign.schema.kinds import DISPERSION_KEYS, KINDS
from ideas_hpc.campaign.schema.read_settings import Settings, expand, set_keys
from ideas_hpc.campaign.schema.toml_file import CampaignSource, apply_overrides, parse_override
from ideas_hpc.design.api.methods import METHODS

CAMPAIGNS = Path(__file__).resolve().parent.parent / "campaigns"
ANGLES = "swarm.angles_rad=[0.5, 2.5, 4.5]"

#: name -> the --set lines of a minimal valid campaign (body: the built-in ellipsoid)
VARIANTS = {
    "flyby": ['kind="flyby"', ANGLES],
    "flyby-simulated": ['kind="flyby"', ANGLES, 'attitude.mode="simulated"'],
    "flyby-encounter": ['kind="flyby"', ANGLES, 'flyby.geometry="encounter"'],
    "design-nadir-exact": ['kind="design-nadir"'],
    "design-nadir-ga": ['kind="design-nadir"', 'design.method="ga"'],
    "design-nadir-p": ['kind="design-nadir"', "design.success_probability=0.5",
                       "monte_carlo.sigma_position_m=10.0"],
    "design-fov": ['kind="design-fov"', ANGLES],
    "design-pareto": ['kind="design-pareto"'],
    "monte-carlo": ['kind="monte-carlo"', ANGLES],
    "monte-carlo-simulated": ['kind="monte-carlo"', ANGLES, 'attitude.mode="simulated"'],
    "monte-carlo-encounter": ['kind="monte-carlo"', ANGLES, 'flyby.geometry="encounter"'],
}

#: dotted key -> the --set lines that give it a valid value other than its default (with a
#: companion read by every variant where the value needs one). Every schema key is here.
VALUES = {
    "seed": ["seed=7"], "description": ['description="x"'],
    "body.name": ['body.name="sphere"'], "body.params": ['body.params="eros"'],
    "body.resolution": ["body.resolution=2"], "body.data_path": ['body.data_path="/nowhere"'],
    "body.length_unit": ['body.length_unit="m"'], "body.shape": ['body.shape="/nowhere/x.obj"'],
    "body.spice_body": ['body.spice_body="EROS"'], "body.spice_frame": ['body.spice_frame="X"'],
    "instrument.ground_resolution_m": ["instrument.ground_resolution_m=2.0"],
    "instrument.aperture_cm": ["instrument.aperture_cm=10.0"],
    "instrument.wavelength_um": ["instrument.wavelength_um=0.6"],
    "instrument.min_elevation_deg": ["instrument.min_elevation_deg=10.0"],
    "instrument.near_field_mm": ["instrument.near_field_mm=500.0"],
    "instrument.image_rate_hz": ["instrument.image_rate_hz=2.0"],
    "instrument.half_angle_deg": ["instrument.half_angle_deg=5.0"],
    "instrument.pixel_pitch_um": ["instrument.pixel_pitch_um=10.0",
                                  "instrument.focal_length_mm=100.0"],
    "instrument.focal_length_mm": ["instrument.focal_length_mm=100.0",
                                   "instrument.pixel_pitch_um=10.0"],
    "instrument.pixels_across": ["instrument.pixels_across=1024"],
    "instrument.exposure_ms": ["instrument.exposure_ms=5.0"],
    "instrument.smear_pixels": ["instrument.smear_pixels=2.0"],
    "instrument.settle_deg": ["instrument.settle_deg=0.5"],
    "flyby.configuration": ['flyby.configuration="helix"'], "flyby.t0_s": ["flyby.t0_s=10.0"],
    "flyby.tf_s": ["flyby.tf_s=300.0"], "flyby.z_start_km": ["flyby.z_start_km=-20.0"],
    "flyby.z_stop_km": ["flyby.z_stop_km=20.0"], "flyby.helix_rise_km": ["flyby.helix_rise_km=1.0"],
    "flyby.d_sep_km": ["flyby.d_sep_km=20.0"], "flyby.tolerance_m": ["flyby.tolerance_m=0.1"],
    "flyby.max_iterations": ["flyby.max_iterations=10"], "flyby.dt_s": ["flyby.dt_s=0.2"],
    "flyby.epoch_s": ["flyby.epoch_s=100.0"], "flyby.geometry": ['flyby.geometry="encounter"'],
    "flyby.speed_km_s": ["flyby.speed_km_s=5.0"],
    "flyby.approach_dec_deg": ["flyby.approach_dec_deg=45.0"],
    "flyby.approach_ra_deg": ["flyby.approach_ra_deg=30.0"],
    "flyby.phase_angle_deg": ["flyby.phase_angle_deg=60.0"],
    "flyby.v_inf_km_s": ["flyby.v_inf_km_s=[0.0, 0.0, 10.0]"],
    "flyby.before_km": ["flyby.before_km=20.0"], "flyby.after_km": ["flyby.after_km=20.0"],
    "flyby.before_s": ["flyby.before_s=100.0"], "flyby.after_s": ["flyby.after_s=100.0"],
    "flyby.epoch_utc": ['flyby.epoch_utc="2000-01-01T12:00:00"'],
    "flyby.spice_spacecraft": ['flyby.spice_spacecraft="NEAR"'],
    "swarm.angles_rad": ["swarm.angles_rad=[0.1, 2.0, 4.0]"],
    "swarm.sweep_periods_min": ["swarm.sweep_periods_min=[1.0, 1.0, 1.0]"],
    "swarm.min_separation_km": ["swarm.min_separation_km=0.5"],
    "attitude.mode": ['attitude.mode="simulated"'],
    "attitude.maneuver": ['attitude.maneuver="track"', 'flyby.geometry="encounter"'],
    "attitude.decimate": ["attitude.decimate=5"], "attitude.theta_max_deg": ["attitude.theta_max_deg=1.0"],
    "dynamics": ['dynamics.gravity="point_mass"'], "spacecraft": ["spacecraft.mass=5.0"],
    "controller": ['controller.preset="fov"'], "coverage": ['coverage.mode="exact"'],
    "torques": ["torques.constant.torque_B_N_m=[0.0, 0.0, 1e-6]"],
    "design.method": ['design.method="ga"'], "design.angle_step_deg": ["design.angle_step_deg=2.0"],
    "design.time_limit_s": ["design.time_limit_s=10.0"],
    "design.failures_tolerated": ["design.failures_tolerated=1"],
    "design.verify_samples": ["design.verify_samples=40"],
    "design.success_probability": ["design.success_probability=0.5"],
    "design.confidence": ["design.confidence=0.9"], "design.scenarios": ["design.scenarios=40"],
    "design.demonstrate": ["design.demonstrate=true"],
    "design.demonstrate_looks": ["design.demonstrate_looks=2"],
    "design.bank_level": ["design.bank_level=0.6"], "design.population": ["design.population=10"],
    "design.holdout_scenarios": ["design.holdout_scenarios=40"],
    "design.verify_samples_max": ["design.verify_samples_max=512"],
    "design.tolerant_markers": ["design.tolerant_markers=true"],
    "design.curve_samples": ["design.curve_samples=0"],
    "design.ca_distances_km": ["design.ca_distances_km=[100,130]"],
    "design.target_rule": ['design.target_rule="full"'],
    "design.coverage_reference": ['design.coverage_reference="lit_at_tca"'],
    "design.generations": ["design.generations=5"], "design.n_max": ["design.n_max=10"],
    "design.eps_tol_pct": ["design.eps_tol_pct=1.0"],
    "design.angle_step_rad": ["design.angle_step_rad=0.05"],
    "design.p_min_min": ["design.p_min_min=0.5"], "design.p_max_min": ["design.p_max_min=5.0"],
    "design.period_step_min": ["design.period_step_min=0.2"], "design.parents": ["design.parents=4"],
    "design.elitism": ["design.elitism=1"], "design.mutation_probability": ["design.mutation_probability=0.2"],
    "design.stall_generations": ["design.stall_generations=3"], "design.chunk_size": ["design.chunk_size=8"],
    "design.nadir_store": ['design.nadir_store="/nowhere/np.zarr"'],
    "design.objectives": ['design.objectives=["n", "worst_failure_coverage"]'],
    "monte_carlo.samples": ["monte_carlo.samples=10"],
    "monte_carlo.attitude_dispersion": ["monte_carlo.attitude_dispersion=false"],
    "monte_carlo.attitude_start": ['monte_carlo.attitude_start="acquisition"'],
    "monte_carlo.acquisition_s": ["monte_carlo.acquisition_s=100.0"],
    "monte_carlo.sigma_attitude_deg": ["monte_carlo.sigma_attitude_deg=0.05"],
    "monte_carlo.sigma_rate_rad_s": ["monte_carlo.sigma_rate_rad_s=1e-4"],
    "monte_carlo.sigma_c20_pct": ["monte_carlo.sigma_c20_pct=1.0"],
    "monte_carlo.sigma_c22_pct": ["monte_carlo.sigma_c22_pct=1.0"],
    "monte_carlo.sigma_gm_pct": ["monte_carlo.sigma_gm_pct=1.0"],
    "monte_carlo.reflectivity_min": ["monte_carlo.reflectivity_min=0.5"],
    "monte_carlo.reflectivity_max": ["monte_carlo.reflectivity_max=0.7"],
    "monte_carlo.sigma_position_m": ["monte_carlo.sigma_position_m=20.0"],
    "monte_carlo.sigma_velocity_mm_s": ["monte_carlo.sigma_velocity_mm_s=1.0"],
    "monte_carlo.failures_k": ["monte_carlo.failures_k=1"],
    "monte_carlo.failure_probability": ["monte_carlo.failure_probability=0.1"],
    "monte_carlo.sigma_misalignment_deg": ["monte_carlo.sigma_misalignment_deg=0.1"],
    "monte_carlo.failure_probability_sd": ["monte_carlo.failure_probability_sd=0.01",
                                           "monte_carlo.failure_probability=0.1"],
    "monte_carlo.failure_probability_values": ["monte_carlo.failure_probability_values=[0.01, 0.1]"],
    "monte_carlo.common_cause_beta": ["monte_carlo.common_cause_beta=0.1",
                                      "monte_carlo.failure_probability=0.1"],
    "monte_carlo.common_cause_groups": ["monte_carlo.common_cause_groups=[[0, 1], [2]]",
                                        "monte_carlo.common_cause_beta=0.1",
                                        "monte_carlo.failure_probability=0.1"],
    "monte_carlo.failure_in_pass_share": ["monte_carlo.failure_in_pass_share=0.5",
                                          "monte_carlo.failure_probability=0.1"],
    "run.chunk_size": ["run.chunk_size=4"], "run.workers": ["run.workers=2"],
    "run.device": ['run.device="cuda"'],
    "target.prior": ['target.prior="eros-class"'],
    **{f"target.{k}": [f"target.{k}={v}", 'target.prior="eros-class"']
       for k, v in (("sigma_r", 0.1), ("correlation_deg", 40.0), ("sigma_diameter_pct", 5.0),
                    ("sigma_pole_deg", 2.0), ("p_mirror", 0.5), ("sigma_phase_deg", 5.0),
                    ("lightcurve_days", 10.0))},
    "navigation.preset": ['navigation.preset="arrokoth"'],
    "navigation.bplane_major_km": ["navigation.bplane_major_km=30.0"],
    "navigation.bplane_minor_km": ["navigation.bplane_minor_km=3.0",
                                   "navigation.bplane_major_km=30.0"],
    "navigation.bplane_angle_deg": ["navigation.bplane_angle_deg=30.0",
                                    'navigation.preset="lutetia"'],
    "navigation.tca_sigma_s": ["navigation.tca_sigma_s=2.0", 'navigation.preset="lutetia"'],
    "navigation.member_sigma_km": ["navigation.member_sigma_km=0.2",
                                   'navigation.preset="lutetia"'],
    "navigation.update": ['navigation.update="2 days out"', 'navigation.preset="lutetia"'],
    "navigation.terminal_pixels": ["navigation.terminal_pixels=5.0",
                                   'navigation.preset="lutetia"'],
    "navigation.centroid_sigma_deg": ["navigation.centroid_sigma_deg=0.01",
                                      'navigation.preset="lutetia"'],
}
#: Keys whose valid value needs files: every variant reads them (checked on the
#: declaration; tests/test_spice_in.py loads real kernels).
NEEDS_FILES = {"body.kernels"}


def schema_keys() -> list[str]:
    """Every key a campaign file can set, dotted (a model's table by its name)."""
    out = []
    for key, spec in SCHEMA.items():
        if isinstance(spec, dict):
            out += [f"{key}.{k}" for k, f in spec.items() if isinstance(f, Field)]
        elif key != "kind":
            out.append(key)
    return out


def _source(sets: list[str]) -> CampaignSource:
    data = apply_overrides({"body": {"name": "ellipsoid"}}, sets)
    return CampaignSource(data, None, {}, list(sets))


def _load(sets: list[str], resolved: bool = False):
    src = _source(sets)
    src.resolved = resolved
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)     # design.angle_step_rad's
        return validate_campaign(src)


def _settings(c) -> Settings:
    return Settings(c.config, c.raw)


def test_the_values_cover_every_key_and_the_variants_every_kind():
    assert set(VALUES) | NEEDS_FILES == set(schema_keys())
    kinds = {parse_override(v[0])[1] for v in VARIANTS.values()}
    assert kinds == set(KINDS)
    nadir = [v for v in VARIANTS.values() if v[0] == 'kind="design-nadir"']
    methods = {parse_override(s)[1] for v in nadir for s in v if s.startswith("design.method")}
    assert methods | {"exact"} == set(METHODS)


@pytest.mark.parametrize("variant", VARIANTS)
def test_every_key_is_read_or_refused_by_name(variant):
    base = VARIANTS[variant]
    before = _settings(_load(base))         # the variant itself loads
    ours = set(set_keys(_source(base).data, SCHEMA))
    bad = []
    for key, sets in VALUES.items():
        try:
            c = _load(base + sets)
        except InputError as exc:
            if exc.field == key:
                continue
            try:
                after = _settings(_load(base + sets, resolved=True))
            except InputError as other:
                bad.append(f"{key}: refused naming {exc.field!r}: {exc.message} ({other})")
                continue
            switched = (exc.field in ours and reads.is_read(exc.field, before)
                        and not reads.is_read(exc.field, after) and reads.is_read(key, after))
            if not switched:
                bad.append(f"{key}: refused naming {exc.field!r}: {exc.message}")
            continue
        if not reads.is_read(key, _settings(c)):
            bad.append(f"{key}: loaded, yet declared unread")
    for key in NEEDS_FILES:
        assert reads.is_read(key, before), key
    assert not bad, f"{variant}:\n" + "\n".join(bad)


def test_every_declared_key_is_a_schema_key():
    """A typo in a declaration would declare nothing (and refuse nothing)."""
    keys = set(schema_keys())
    listed = {k for kind in KINDS.values() for _, r in kind.entries() for k in expand(r)
              if k != DISPERSION_KEYS}
    assert listed <= keys, listed - keys
    assert set(reads.RULES) <= keys, set(reads.RULES) - keys


@pytest.mark.parametrize("path", sorted(CAMPAIGNS.rglob("*.toml")), ids=lambda p: p.name)
def test_every_shipped_campaign_loads(path):
    load(path)


def test_a_refusal_names_the_kind_the_setting_and_who_reads_it(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text('kind = "design-nadir"\n[body]\nname = "ellipsoid"\n[design]\n'
                 "population = 50\n")
    with pytest.raises(InputError) as exc:
        load(f)
    e = exc.value
    assert (e.field, e.file, e.line) == ("design.population", str(f), 5)
    assert "design-nadir' with design.method = 'exact'" in e.message
    assert "design.method = 'ga'" in e.message and "'design-fov'" in e.message
    with pytest.raises(InputError) as exc:
        load(CAMPAIGNS / "eros-design.toml", ["monte_carlo.samples=100"])
    assert exc.value.file == "--set" and "design.verify_samples" in exc.value.message


def test_failures_k_in_a_success_probability_design_is_one_switch(monkeypatch):
    """Refused with one line until the design's failure model flies exactly k failures;
    then one declaration (``reads.FAILURES_K_HONOURED``) lets it through."""
    sets = ["monte_carlo.failures_k=1", 'body.name="ellipsoid"']
    monkeypatch.setattr(reads, "FAILURES_K_HONOURED", False)
    with pytest.raises(InputError) as exc:
        load(CAMPAIGNS / "eros-design.toml", sets)
    assert exc.value.field == "monte_carlo.failures_k"
    assert "success-probability design" in exc.value.message
    load(CAMPAIGNS / "eros-nadir.toml", sets)        # the exact design's verification flies it
    monkeypatch.setattr(reads, "FAILURES_K_HONOURED", True)
    load(CAMPAIGNS / "eros-design.toml", sets)


def test_a_stores_resolved_config_is_not_judged():
    """ideas-hpc validate and export re-read a store's config, every default written out."""
    c = load(CAMPAIGNS / "eros-nadir.toml")
    cfg = dict(resolved_config(c))
    cfg.pop("models")
    with pytest.raises(InputError):     # judged as a file, it sets GA keys, samples, ...
        validate_campaign(CampaignSource(data=cfg))
    validate_campaign(CampaignSource(data=cfg, resolved=True))


def test_a_file_key_switched_off_by_set_is_warned_not_refused(tmp_path, capsys):
    """Turning a setting off from the command line still runs: the file's own keys that
    only the file's setting read are named in one warning line each (file and line),
    never silently ignored; the same key given with --set is refused."""
    base = CAMPAIGNS / "eros-design.toml"
    c = load(base, ["design.demonstrate=false", 'body.name="ellipsoid"'])
    err = capsys.readouterr().err
    assert not c.config.design.demonstrate
    line = [ln for ln in err.splitlines() if "design.demonstrate_looks" in ln]
    assert len(line) == 1 and "warning" in line[0] and "switched off by --set" in line[0]
    assert f"{base}:" in line[0]
    with pytest.raises(InputError, match="design.demonstrate_looks"):
        load(base, ["design.demonstrate=false", "design.demonstrate_looks=2"])
    with pytest.raises(InputError, match="design.population"):     # not switched off: unread
        load(base, ["design.population=50"])
