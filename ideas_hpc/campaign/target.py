"""The campaign's target prior (``[target]``, :mod:`ideas_hpc.campaign.schema.target_table`).

``prior = "known"`` changes nothing: the setup flies ``[body]`` in every scenario
(``FlybySetup.target`` is None). ``prior = "eros-class"`` builds
:func:`~ideas_hpc.body.target_prior.eros_class_prior` with the table's overrides and
supplies the body (:func:`prior_body`): the prior's nominal ellipsoid with Eros' Table 1
parameters (orbit, mass, spin period, C20/C22) and the prior's estimated pole, its
prime meridian set so that the nominal body's rotation angle at closest approach is the
prior's nominal phase there. That nominal body defines the flight frame; each scenario's
world is placed in it (:mod:`ideas_hpc.flyby.target_world`).
"""

from __future__ import annotations

import dataclasses
import math

from ideas_hpc.body.bodies import Body
from ideas_hpc.body.params import get_params
from ideas_hpc.body.random_sphere import ShapeFamily
from ideas_hpc.body.shape import build_shape
from ideas_hpc.body.spin_prior import angles_from_unit
from ideas_hpc.body.target_prior import TargetPrior, eros_class_prior
from ideas_hpc.flyby.encounter import approach_speed, window_s


def target_prior(c) -> TargetPrior | None:
    """The campaign's prior with the ``[target]`` overrides, or None for ``"known"``."""
    t = c.config.target
    if t.prior == "known":
        return None
    fam = ShapeFamily()
    fam = dataclasses.replace(
        fam, sigma=fam.sigma if t.sigma_r is None else float(t.sigma_r),
        correlation_angle_rad=(fam.correlation_angle_rad if t.correlation_rad is None
                               else float(t.correlation_rad)))
    prior = eros_class_prior(c.config.body.resolution, family=fam)
    size, pole, rot = prior.size, prior.pole, prior.rotation
    if t.sigma_diameter is not None:
        size = dataclasses.replace(size, sigma_diameter_m=t.sigma_diameter * prior.diameter_m)
    if t.sigma_pole_rad is not None:
        pole = dataclasses.replace(pole, sigma_rad=float(t.sigma_pole_rad))
    if t.p_mirror is not None:
        pole = dataclasses.replace(pole, p_mirror=float(t.p_mirror))
    if t.sigma_phase_rad is not None:
        rot = dataclasses.replace(rot, sigma_phase_epoch_rad=float(t.sigma_phase_rad))
    if t.lightcurve_s is not None:
        rot = dataclasses.replace(rot, dt_epoch_to_tca_s=float(t.lightcurve_s))
    return dataclasses.replace(prior, size=size, pole=pole, rotation=rot)


def tca_time_s(cfg) -> float:
    """Flyby time of closest approach the setup will resolve: the encounter's
    ``t0 + before`` (:func:`ideas_hpc.flyby.encounter.window_s`), or the paper pass's
    mid-window (:func:`ideas_hpc.flyby.target_world.t_tca_s`)."""
    fb = cfg.flyby
    if fb.geometry != "encounter":
        return 0.5 * (fb.t0_s + fb.tf_s)
    speed = approach_speed(fb.v_inf_m_s, fb.speed_m_s)
    before, _ = window_s(speed, 1.0 / cfg.instrument.image_rate_hz, fb.before_s, fb.after_s,
                         fb.before_m, fb.after_m)
    return fb.t0_s + before


def prior_body(prior: TargetPrior, cfg) -> Body:
    """The nominal body of a drawn prior (module docstring)."""
    nom = prior.nominal
    shape = build_shape(nom.base_vertices * nom.stretch, nom.faces, name=nom.name,
                        source=f"nominal of the {prior.name} prior: {nom.source}")
    lon, lat = angles_from_unit(prior.pole.pole_N)
    base = get_params("eros")
    t_abs = cfg.flyby.epoch_s + tca_time_s(cfg)
    w0 = (prior.rotation.phase_tca_nominal_rad - base.spin_rate * t_abs) % (2.0 * math.pi)
    params = dataclasses.replace(base, pole_ra=lon, pole_dec=lat, prime_meridian=w0)
    return Body(prior.name, shape, params,
                f"the {prior.name} prior's nominal (no data file read): {nom.source}")
