"""A campaign's flyby setup: the validated file resolved to a :class:`FlybySetup` (SI),
and its coverage requirement (:func:`requirement_from_campaign`).

The campaign layer builds the setup: it loads the body, sizes the flyby, picks
the maneuver, checks the ring spacing and, for ``flyby.geometry = "encounter"``,
resolves the approach and the imaging window (SPEC sections 2-3, 7c). The flyby
layer below names its own parameters in errors (``d_sep_m``, ``phase_angle_rad``);
:func:`ideas_hpc.campaign.schema.model_fields.flyby_errors` turns them into the file's keys
with their file and line.
"""

from __future__ import annotations

import dataclasses

from ideas_hpc.attitude import campaign_maneuver
from ideas_hpc.attitude.torque_terms import torques_from_config
from ideas_hpc.attitude.device import check_device
from ideas_hpc.attitude.modes import attitude_start
from ideas_hpc.campaign.body_checks import check_body, check_grid_step, check_pointing
from ideas_hpc.body.bodies import load_body
from ideas_hpc.body.formats import load_shape_file
from ideas_hpc.campaign.schema.spice_table import apply_spice
from ideas_hpc.campaign.schema.model_fields import flyby_errors
from ideas_hpc.campaign.target import prior_body, target_prior
from ideas_hpc.campaign.schema.navigation_table import navigation_plan
from ideas_hpc.campaign.schema.instrument_table import exposure_ms
from ideas_hpc.base.units import MM
from ideas_hpc.dynamics.trajectory import sun_direction_T
from ideas_hpc.base.errors import InputError
from ideas_hpc.flyby.encounter import Encounter, approach_angles, approach_speed, window_s
from ideas_hpc.flyby.flight import FlybySetup
from ideas_hpc.flyby.sizing import size_flyby
from ideas_hpc.flyby.swarm_geometry import check_separation
from ideas_hpc.flyby.usable import ImageUse, ifov_rad
from ideas_hpc.mapping.requirement import Requirement


def requirement_from_campaign(c) -> Requirement:
    """The campaign's coverage :class:`~ideas_hpc.mapping.requirement.Requirement`:
    ``design.eps_tol_pct`` (already a fraction, ``config.design.eps_tol``),
    ``design.target_rule``, ``design.coverage_reference`` and the ``[coverage]`` options
    as its observation limits (the very object the setup's ``coverage`` is). Every kind
    builds it here, once."""
    d = c.config.design
    return Requirement(eps_tol=d.eps_tol, limits=c.extras["coverage"], rule=d.target_rule,
                       reference=d.coverage_reference)


def requirement_attrs(requirement: Requirement) -> dict:
    """The store attrs that say what a design's coverage is (issue 42): the reference
    (``coverage_reference``), the requirement's kind and its one-line label."""
    return {"coverage_reference": requirement.reference, "requirement_kind": requirement.kind,
            "requirement": requirement.label}


def setup_from_campaign(c, *, maneuver: str | None = None) -> FlybySetup:
    """Resolve a validated :class:`~ideas_hpc.campaign.schema.campaign_tables.Campaign` to a setup.

    ``maneuver`` (a campaign name of :data:`~ideas_hpc.attitude.MANEUVERS`) overrides
    ``attitude.maneuver`` (the FoV design kind sweeps whatever the file says).
    """
    cfg = c.config
    b = cfg.body
    params = b.params
    if isinstance(params, dict):
        from ideas_hpc.body.params import params_from_mapping
        try:
            params = params_from_mapping(params, prefix="body.params.")
        except InputError as exc:
            raise c.source.locate(exc) from None
    prior = target_prior(c)     # None: [target] prior = "known", the [body] itself
    try:
        body = prior_body(prior, cfg) if prior is not None else load_body(
            b.name, data_path=b.data_path, resolution=b.resolution, params=params,
            length_unit=b.length_unit)
        body.require_params()
        if b.shape is not None:     # a mesh (DSK...) for the named body, its parameters kept
            body = _replace_shape(c, body, b)
        if isinstance(b.params, dict):
            body = _default_degree2(body, b.params)
        body = dataclasses.replace(body, params=apply_spice(body.params, c.extras.get("spice")))
    except InputError as exc:
        if exc.field in (None, "body", "body.params", "data_path"):
            f = {"data_path": "body.data_path", None: "body.name"}.get(exc.field, exc.field)
            msg = f"{exc.message}: {exc.file}" if exc.file else exc.message
            raise c.error(msg, "body.name" if f == "body" else f) from None
        raise c.source.locate(exc) from None
    check_body(c, body)
    try:    # before anything is flown: cuda where there is none is one line, exit 2
        device = check_device(cfg.run.device, "run.device")
    except InputError as exc:
        raise c.error(exc.message, "run.device") from None
    inst = cfg.instrument
    sizing = size_flyby(r_max=body.shape.r_max, r_min=body.shape.r_min,
                        ground_resolution=inst.ground_resolution_m,
                        aperture=inst.aperture_m, wavelength=inst.wavelength_m,
                        min_elevation=inst.min_elevation_rad, near=inst.near_field_m)
    with flyby_errors(c):
        man = campaign_maneuver(maneuver or cfg.attitude.maneuver)
    eta = inst.half_angle_rad
    if eta is None:
        eta = man.half_angle(sizing.eta_nadir)
    fb = cfg.flyby
    att = cfg.attitude
    ex = c.extras
    d_sep = fb.d_sep_m if fb.d_sep_m is not None else sizing.d_sep
    sw = cfg.swarm
    if sw.angles_rad and fb.configuration == "ring":
        with flyby_errors(c):
            check_separation(sw.angles_rad, d_sep, sw.min_separation_m)
    check_grid_step(c, d_sep)
    check_pointing(c, eta, d_sep - sizing.r_av)
    t0, tf, enc, epoch_s = fb.t0_s, fb.tf_s, None, fb.epoch_s
    spice = c.extras.get("spice")
    if spice is not None and spice.v_inf_T_m_s is not None:     # the spacecraft SPK's approach
        fb = dataclasses.replace(fb, v_inf_m_s=list(spice.v_inf_T_m_s))
    if fb.geometry == "encounter":
        with flyby_errors(c):
            t0, tf, enc = _encounter_window(fb, body, 1.0 / inst.image_rate_hz)
        if spice is not None and spice.ca_et_s is not None:    # closest approach at its epoch
            epoch_s = spice.ca_et_s - spice.epoch_et_s - enc.t_ca_s
    return FlybySetup(
        body=body, sizing=sizing, t0_s=t0, tf_s=tf, dt_s=fb.dt_s,
        image_dt_s=1.0 / inst.image_rate_hz,
        d_sep_m=d_sep,
        z_start_m=fb.z_start_m, z_stop_m=fb.z_stop_m, configuration=fb.configuration,
        helix_rise_m=fb.helix_rise_m, eta_rad=eta, near_m=sizing.near, far_m=sizing.far,
        theta_max_rad=att.theta_max_rad if att.theta_max_rad is not None else sizing.theta_max,
        maneuver=man, attitude_mode=att.mode, decimate=att.decimate,
        tol_m=fb.tolerance_m, max_iter=fb.max_iterations, seed=cfg.seed,
        force_model=ex["force_model"], spacecraft=ex["spacecraft"],
        gains=ex["gains"], coverage=ex["coverage"], p_min_s=cfg.design.p_min_s,
        epoch_s=epoch_s, encounter=enc, imaging=_imaging(cfg, eta),
        attitude_start=cfg.monte_carlo.attitude_start,
        torques=torques_from_config(c.raw.get("torques"), prefix="torques."),
        device=device, target=prior,
        # read only when the file has the table: a run without one reads none of its keys
        navigation=_navigation(cfg, eta, sizing) if c.raw.get("navigation") else None)


def _navigation(cfg, eta_rad: float, sizing):
    """The ``[navigation]`` table's plan (None without one); terminal tracking's lock range
    for a body of the mean diameter ``2 r_av`` seen with the instrument's IFOV."""
    inst = cfg.instrument
    ifov = 1.0
    if cfg.navigation.terminal_pixels is not None:
        ifov = ifov_rad(eta_rad, pixels_across=inst.pixels_across,
                        pixel_pitch_m=inst.pixel_pitch_m, focal_length_m=inst.focal_length_m,
                        wavelength_m=inst.wavelength_m, aperture_m=inst.aperture_m)
    return navigation_plan(cfg.navigation, 2.0 * sizing.r_av, ifov)


def _imaging(cfg, eta_rad: float) -> ImageUse | None:
    """The usable-image test (SPEC 7d), or None (every image counts) for a start without
    ``usable_images`` (the paper's, ``monte_carlo.attitude_start = "paper"``). Perfect
    tracking faces it where its geometry tests ideal images
    (:attr:`~ideas_hpc.flyby.geometry.Geometry.ideal_images_tested`), and the paper's start
    turns it off there too."""
    if not attitude_start(cfg.monte_carlo.attitude_start).usable_images:
        return None
    inst = cfg.instrument
    return ImageUse(ifov_rad(eta_rad, pixels_across=inst.pixels_across,
                             pixel_pitch_m=inst.pixel_pitch_m, focal_length_m=inst.focal_length_m,
                             wavelength_m=inst.wavelength_m, aperture_m=inst.aperture_m),
                    exposure_s=exposure_ms(cfg) * MM,
                    smear_pixels=inst.smear_pixels,
                    settle_rad=inst.settle_rad)


def _encounter_window(fb, body, image_dt_s: float):
    """``(t0, tf, Encounter)`` of ``flyby.geometry = "encounter"`` (SPEC section 7c) from the
    typed ``[flyby]`` table ``fb`` (SI)."""
    speed = approach_speed(fb.v_inf_m_s, fb.speed_m_s)
    before, after = window_s(speed, image_dt_s, fb.before_s, fb.after_s, fb.before_m, fb.after_m)
    t_ca = fb.t0_s + before
    sun = sun_direction_T(body.params, [fb.epoch_s + t_ca])[0]
    speed, ra, dec = approach_angles(fb.v_inf_m_s, fb.speed_m_s, fb.approach_ra_rad,
                                     fb.approach_dec_rad, fb.phase_angle_rad, sun)
    return fb.t0_s, t_ca + after, Encounter(speed, ra, dec, t_ca)


def _default_degree2(body, table: dict):
    """A ``[body.params]`` table that gives neither ``c20_km2`` nor ``c22_km2`` gets the
    constant-density values of its mesh (:mod:`ideas_hpc.body.mass_properties`, the
    values ``ideas-hpc body FILE`` prints) instead of a point mass's zeros."""
    if "c20_km2" in table or "c22_km2" in table:
        return body
    props = body.shape.mass_properties
    params = dataclasses.replace(body.params, c20=props.c20_m2, c22=props.c22_m2)
    return dataclasses.replace(body, params=params)


def _replace_shape(c, body, b):
    """``body`` with the mesh of ``[body] shape``; its errors name ``body.shape``."""
    try:
        shape = load_shape_file(b.shape, length_unit=b.length_unit)
    except InputError as exc:
        where = f" ({exc.file}{':' + str(exc.line) if exc.line else ''})" if exc.file else ""
        raise c.error(f"{exc.message}{where}", "body.shape") from None
    return dataclasses.replace(body, shape=shape, note=f"{body.note}; shape {b.shape}")
