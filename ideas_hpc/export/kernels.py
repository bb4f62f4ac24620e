"""``ideas-hpc export STORE``: a store's swarm as SPICE kernels and a CSV of images (issue 32).

A store holds the trajectory at the stored steps and the camera attitude at a few
snapshots; the export flies the store's swarm again from its resolved config (the
reproducibility promise) and writes at full resolution. Which flight, by store kind: a
flyby's, a design's chosen swarm, a Monte Carlo store's nominal flight or, with
``--sample K``, its sample K; a store of many swarms (a Pareto front) is refused
(:mod:`ideas_hpc.export.flight`, which also refuses a re-flown trajectory more
than 1 mm from the stored one). Files (SPEC section 7e,
:mod:`ideas_hpc.export.writers`):

* ``swarm.bsp``: SPK type 13, each spacecraft relative to the body centre in J2000;
* ``swarm.bc`` + ``swarm.tsc``: CK type 3 of each camera frame (+z the boresight) at
  every image, with its SCLK;
* ``swarm.tf``: the frame kernel naming the camera frames and the body frame
  ``IDEAS_<ID>_FIXED``, and ``body.tpc``: that frame's orientation (IAU form);
* ``images.csv``: one row per spacecraft and image: times (flyby s, TDB s past J2000,
  UTC when a leap-second kernel is known), position (m, J2000, body-centred), the
  quaternion J2000 -> camera (SPICE's ``m2q`` convention, scalar first), the unit Sun
  direction (J2000) and whether the image was usable: the body in the field of view
  (:func:`body_in_view`), for simulated attitude the smear and settle test the
  coverage applied (:func:`ideas_hpc.flyby.camera.usable_mask`) and, in a dispersed
  sample, the spacecraft not failed;
* ``export.tm``: a meta-kernel loading them (and the LSK when known).

Epoch: the store's ``models.spice.epoch_et_s`` (a run from kernels) or ``--epoch-et``
(TDB s past J2000 of the body's element epoch; default 0). NAIF IDs: spacecraft
``naif_base - k`` (negative, as NAIF reserves for spacecraft), the body from its SPICE
name, ``--body-id``, or 2000433 for Eros.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np

from ideas_hpc.base.errors import InputError
from ideas_hpc.body.formats import family_of


def add_export_command(sub) -> None:
    p = sub.add_parser("export", help="write a store's swarm as SPICE kernels (SPK, CK, FK, "
                                      "PCK) and a CSV of every image",
                       description=__doc__.split("\n\n")[1])
    p.add_argument("store", help="zarr store of a flyby, design or Monte Carlo campaign")
    p.add_argument("--out", default=None, help="output folder (default: STORE-spice)")
    p.add_argument("--naif-base", type=int, default=-1000,
                   help="NAIF ID of spacecraft 0; spacecraft k gets base - k (default -1000)")
    p.add_argument("--body-id", type=int, default=None, help="NAIF ID of the body")
    p.add_argument("--epoch-et", type=float, default=None,
                   help="TDB s past J2000 of the body's element epoch (default 0, or the "
                        "store's kernel epoch)")
    p.add_argument("--lsk", default=None, help="leap-second kernel, for the UTC column")
    p.add_argument("--sample", type=int, default=None, metavar="K",
                   help="Monte Carlo store: export sample K (default: the nominal flight)")
    p.set_defaults(handler=_cmd_export)


def _cmd_export(a) -> int:
    notes: list = []
    out = export_store(a.store, a.out, naif_base=a.naif_base, body_id=a.body_id,
                       epoch_et=a.epoch_et, lsk=a.lsk, sample=a.sample, notes=notes)
    print("\n".join(notes + [f"wrote {out}"]))
    return 0


def _body_id(sp, c, spice, body_id):
    if body_id is not None:
        return body_id
    if spice:
        return int(sp.bods2c(spice["spice_body"]))
    family = family_of(Path(str(c.config.body.name)).stem)
    if family is not None and family.naif_id is not None:
        return family.naif_id
    raise InputError(f"body {c.config.body.name!r} has no known NAIF ID; give one",
                     field="--body-id")


def export_store(store, out=None, *, naif_base: int = -1000, body_id: int | None = None,
                 epoch_et: float | None = None, lsk=None, sample: int | None = None,
                 notes: list | None = None) -> Path:
    """Write the kernels and the CSV of a store's flight (module docstring); returns the
    folder. ``sample``: a Monte Carlo store's sample (default its nominal flight);
    ``notes``: a list that gets the lines saying which flight was written."""
    from ideas_hpc.export import writers as w
    from ideas_hpc.export.flight import camera_rates_J, flight_of
    from ideas_hpc.engine.store_meta import store_attrs
    from ideas_hpc.base.spice import spiceypy

    sp = spiceypy("export")
    store = Path(store)
    attrs = store_attrs(store)
    if naif_base >= 0:
        raise InputError(f"must be negative (NAIF spacecraft IDs), got {naif_base}",
                         field="--naif-base")
    fl = flight_of(store, attrs, sample)
    if notes is not None:
        notes += [f"flight: {fl.what}", *(f"note: {n}" for n in fl.notes)]
    c, setup = fl.c, fl.setup
    spice = attrs["config"].get("models", {}).get("spice")
    et_el = spice["epoch_et_s"] if spice else (epoch_et if epoch_et is not None else 0.0)
    bid = _body_id(sp, c, spice, body_id)
    params = setup.body.params
    n_sc = fl.position_T.shape[0]
    sc_ids = [naif_base - k for k in range(n_sc)]
    cams = [f"IDEAS_SC{k}_CAMERA" for k in range(n_sc)]
    body_frame = f"IDEAS_{bid}_FIXED"
    out = Path(out) if out else store.with_name(store.name.removesuffix(".zarr") + "-spice")
    out.mkdir(parents=True, exist_ok=True)
    dcm_NJ = np.asarray(sp.pxform("J2000", "ECLIPJ2000", 0.0))
    omega = np.array([0.0, 0.0, params.spin_rate])

    tau = setup.epoch_s + fl.times_s
    tj = w.dcm_TN(params, tau) @ dcm_NJ                       # [T J2000] per step
    r_J = np.einsum("tji,ktj->kti", tj, fl.position_T)
    v_T = fl.velocity_T + np.cross(omega, fl.position_T)     # inertial velocity, in T
    v_J = np.einsum("tji,ktj->kti", tj, v_T)
    (out / "body.tpc").write_text(w.pck_text(bid, params, et_el, dcm_NJ))
    (out / "swarm.tf").write_text(w.fk_text(bid, body_frame, sc_ids, cams))
    t_img = fl.image_times_s
    et_img = et_el + setup.epoch_s + t_img
    (out / "swarm.tsc").write_text(w.sclk_text(sc_ids, float(et_img[0])))
    for name in ("swarm.bsp", "swarm.bc"):
        (out / name).unlink(missing_ok=True)
    w.write_spk(sp, out / "swarm.bsp", bid, sc_ids, et_el + tau, r_J, v_J)
    tj_img = w.dcm_TN(params, setup.epoch_s + t_img) @ dcm_NJ
    dcm_CJ = np.einsum("kiab,ibc->kiac", fl.dcm_BT, tj_img)
    omega_J = camera_rates_J(fl, dcm_CJ)     # the flown rates (simulated attitude)
    if omega_J is None:                       # else central differences, in flyby time
        omega_J = np.stack([w.rates_J(dcm_CJ[k], t_img) for k in range(n_sc)])
    kernels = [out / "swarm.tsc", out / "swarm.tf", out / "body.tpc"]
    lsk = lsk or _lsk_of(attrs)
    for k in kernels:
        sp.furnsh(str(k))
    if lsk:
        sp.furnsh(str(lsk))
    try:
        w.write_ck(sp, out / "swarm.bc", sc_ids, et_img, dcm_CJ, omega_J)
        utc = [sp.et2utc(float(t), "ISOC", 6) for t in et_img] if lsk else [""] * len(et_img)
    finally:
        for k in kernels:
            sp.unload(str(k))
        if lsk:
            sp.unload(str(lsk))
    if not lsk:
        print("ideas-hpc: warning: --lsk: no leap-second kernel, the CSV's utc column is empty",
              file=sys.stderr, flush=True)
    sun_J = np.einsum("tji,tj->ti", tj_img, setup.world.sun_T(t_img))
    r_img_J = np.einsum("tji,ktj->kti", tj_img, fl.r_img_T)
    _write_csv(out / "images.csv", sp, sc_ids, t_img, et_img, utc, r_img_J, dcm_CJ, sun_J,
               usable_images(fl))
    mk = [str(lsk)] if lsk else []
    mk += [str(out / n) for n in ("swarm.tsc", "swarm.tf", "body.tpc", "swarm.bsp", "swarm.bc")]
    (out / "export.tm").write_text("\\begindata\nKERNELS_TO_LOAD = (\n"
                                   + "\n".join(f"  '{k}'" for k in mk) + " )\n\\begintext\n")
    return out


def usable_images(fl) -> np.ndarray:
    """(N, n_img) bool: the CSV's ``usable``: the body in view (:func:`body_in_view`), the
    smear and settle test the coverage applied (simulated attitude; perfect tracking's
    smear test on an encounter, read from the cameras it blinded), the spacecraft not
    failed (a dispersed sample)."""
    from ideas_hpc.flyby.camera import usable_mask

    setup = fl.setup
    ok = body_in_view(fl.r_img_T, fl.dcm_BT, setup.eta_rad, setup.body.shape.r_max)
    sharp = usable_mask(setup, fl.attitude)    # None: ideal attitude, or no test
    if sharp is None and fl.imaging_BT is not None:
        sharp = np.all(np.asarray(fl.imaging_BT) == np.asarray(fl.dcm_BT), axis=(-2, -1))
    if sharp is not None:
        ok &= sharp
    if fl.active is not None:
        ok &= fl.active[:, None]
    return ok


def body_in_view(r_T, dcm_BT, eta_rad: float, r_max_m: float) -> np.ndarray:
    """(N, n_img) bool: the body's bounding sphere (radius ``r_max_m``) meets the cone round
    the camera's square field of view (half angle ``atan(sqrt(2) tan eta)`` to a corner)."""
    rng = np.linalg.norm(r_T, axis=-1)
    bore = dcm_BT[..., 2, :]                      # +z_B in T
    cos_off = np.einsum("kia,kia->ki", bore, -r_T) / rng
    off = np.arccos(np.clip(cos_off, -1.0, 1.0))
    half = np.arctan(np.sqrt(2.0) * np.tan(eta_rad))
    return off <= half + np.arcsin(np.clip(r_max_m / rng, 0.0, 1.0))


def _lsk_of(attrs: dict):
    """The leap-second kernel among the store's ``body.kernels``, if any still exists."""
    ks = (attrs["config"].get("body") or {}).get("kernels") or []
    ks = [ks] if isinstance(ks, str) else ks
    for k in ks:
        if str(k).lower().endswith(".tls") and Path(k).is_file():
            return k
    return None


def _write_csv(path, sp, sc_ids, t_img, et_img, utc, r_J, dcm_CJ, sun_J, usable) -> None:
    with open(path, "w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(["spacecraft", "naif_id", "image", "t_s", "et_tdb_s", "utc", "x_m", "y_m",
                      "z_m", "q0", "q1", "q2", "q3", "sun_x", "sun_y", "sun_z", "usable"])
        for k, sc in enumerate(sc_ids):
            for i in range(len(t_img)):
                q = sp.m2q(np.ascontiguousarray(dcm_CJ[k, i]))
                ok = True if usable is None else bool(np.asarray(usable)[k, i])
                out.writerow([k, sc, i, repr(float(t_img[i])), repr(float(et_img[i])), utc[i],
                              *(repr(float(x)) for x in r_J[k, i]),
                              *(repr(float(x)) for x in q), *(repr(float(x)) for x in sun_J[i]),
                              int(ok)])
