"""What ``ideas-hpc report`` shows of a design under a target prior (issue 42 deliverable 6):
the answers of ``ideas-hpc study`` when the store holds them (their lines,
:mod:`ideas_hpc.campaign.study_lines`, and a figure), a gallery of the prior's worlds (the
bank's first scenarios, each with the designed swarm's P there) and the B-plane error
ellipse of the navigation with the swarm (:mod:`ideas_hpc.plots.study`)."""

from __future__ import annotations

import math
from pathlib import Path

from ideas_hpc.base import seeds
from ideas_hpc.campaign.study import ANSWERS, GROUPS

#: Worlds in the report's gallery.
GALLERY = 8


def study_groups(store) -> dict:
    """``{answer: Dataset}`` of the study answers the store holds."""
    import xarray as xr

    out = {}
    for name in ANSWERS:
        try:
            out[name] = xr.open_zarr(store, group=GROUPS[name], consolidated=False)
        except Exception:       # not stored (zarr's missing-group error differs by version)
            continue
    return out


def study_lines(groups: dict) -> list[str]:
    """One line per stored answer."""
    from ideas_hpc.campaign.study_lines import answer_line

    return [answer_line(name, groups[name]) for name in ANSWERS if name in groups]


def _gallery(st, ds, out: Path):
    from ideas_hpc.campaign.target import target_prior
    from ideas_hpc.plots.prior import prior_gallery

    prior = target_prior(st.c)
    n = min(GALLERY, int(st.c.config.design.scenarios))
    worlds = [prior.draw(int(st.c.config.seed), k, family=seeds.SCENARIO_STREAM)
              for k in range(n)]
    notes = None
    if "scenario_probability" in ds and ds.sizes.get("scenario", 0) >= n:
        notes = [f"P_s = {x:.3f}" for x in ds["scenario_probability"].values[:n]]
    return prior_gallery(worlds, out / "study_prior_gallery.png", notes=notes,
                         title=f"the bank's first {n} worlds of the {prior.name} prior "
                               "(P_s: the designed swarm's P in that scenario)")


def _bplane(st, shape, groups: dict, out: Path):
    from ideas_hpc.campaign.study import bplane_geometry
    from ideas_hpc.plots.study import bplane_figure

    cov, swarm = bplane_geometry(st)
    nav = groups.get("navigation")
    others = () if nav is None else tuple(float(s) for s in nav["bplane_sigma"].values)
    radius = None if shape is None else (
        3.0 * shape.mass_properties.volume_m3 / (4.0 * math.pi)) ** (1.0 / 3.0)
    err = st.setup.navigation.error
    return bplane_figure(cov, swarm, out / "study_bplane.png", d_sep_m=float(st.setup.d_sep_m),
                         other_sigmas_m=others, body_radius_m=radius,
                         title=f"navigation: {err.update or 'the campaign'} "
                               f"(TCA 1-sigma {err.sigma_tca_s:.3g} s)")


def study_figures(store, ds, groups: dict, out: Path, shape=None) -> list[Path]:
    """The study's figures that apply to a success-probability design store (``shape``: the
    store's body, whose volume-equivalent circle the B-plane figure draws)."""
    from ideas_hpc.base.progress import log
    from ideas_hpc.campaign.study import open_study
    from ideas_hpc.plots.study import answers_figure

    figs = []
    if "reliability_threshold" not in ds.attrs:
        return figs
    if groups.get("navigation") is not None or groups.get("per-target") is not None:
        figs.append(answers_figure(groups.get("navigation"), groups.get("per-target"),
                                   out / "study_answers.png",
                                   p=float(ds.attrs["success_probability"])))
    try:
        st = open_study(store)
    except (OSError, KeyError, ValueError) as exc:   # a store the setup cannot be rebuilt
        # for (its body's data absent, an older config): the report's extras only
        log(f"report: no prior gallery or B-plane figure ({exc})")
        return figs
    if st.setup.target is not None:
        figs.append(_gallery(st, ds, out))
    nav = st.setup.navigation
    if nav is not None and nav.error.sigma_major_m > 0 and st.setup.encounter is not None:
        figs.append(_bplane(st, shape, groups, out))
    return figs
