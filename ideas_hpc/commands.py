"""``ideas-hpc run``, ``ideas-hpc report`` (SPEC section 9) and ``ideas-hpc scan-arrival``,
``ideas-hpc scan-encounter``, ``ideas-hpc resolution`` (``body``, ``export``, ``validate``
and ``study`` live beside their code)."""

from __future__ import annotations


def _cmd_run(args) -> int:
    from ideas_hpc.campaign.run import run_file

    sets = list(args.set)
    if args.device is not None:     # the same as --set run.device="..." (docs/gpu.md)
        sets.append(f'run.device="{args.device}"')
    run_file(args.campaign, out=args.out, overrides=sets, workers=args.workers,
             scheduler=args.scheduler, resume=args.resume, cluster=args.cluster,
             slurm_config=args.slurm_config, progress=not args.no_progress)
    return 0


def _cmd_report(args) -> int:
    from ideas_hpc.report.write import write_report

    out = write_report(args.store, args.out, html=args.html, parallel=True)
    print(out.read_text() if out.suffix == ".txt" else out)
    if args.html:
        print(f"interactive report: {out.with_name('report.html')}")
    return 0


def _cmd_scan(args) -> int:
    from ideas_hpc.campaign.scan import scan_file

    scan_file(args.campaign, args.set, n=args.n, span_h=args.span_h, out=args.out)
    return 0


def _cmd_scan_encounter(args) -> int:
    from ideas_hpc.campaign.scan_encounter import scan_encounter_file

    scan_encounter_file(args.campaign, args.set, decs_deg=args.dec_deg,
                        phases_deg=args.phase_deg, step_deg=args.step_deg, out=args.out,
                        plot=args.plot)
    return 0


def _percent_list(text) -> list:
    from ideas_hpc.base.errors import InputError

    try:
        out = [float(e) for e in (text or "").split(",") if e.strip()]
    except ValueError:
        raise InputError(f"expected percentages separated by commas, got {text!r}",
                         field="--eps-tol") from None
    if any(not 0 <= e < 100 for e in out):
        raise InputError(f"each must be in [0, 100) %, got {text!r}", field="--eps-tol")
    return out


def _cmd_resolution(args) -> int:
    from ideas_hpc.campaign.resolution_study import format_table, resolution_study

    rows, path = resolution_study(args.campaign, args.shapes.split(","), overrides=args.set,
                                  out=args.out, workers=args.workers,
                                  progress=not args.no_progress,
                                  eps_list=_percent_list(args.eps_tol))
    print(format_table(rows))
    print(f"table: {path}")
    return 0


def add_commands(sub) -> None:
    import argparse
    import textwrap

    from ideas_hpc.campaign.schema.kinds import KINDS

    kinds = "\n".join(textwrap.fill(f"{k.name:<14} {k.doc}", 78, initial_indent="  ",
                                     subsequent_indent=" " * 17) for k in KINDS.values())
    p = sub.add_parser("run", help="run a campaign file and write a zarr store",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Run a campaign file and write its zarr store. The file's "
                                   "'kind' is one of:\n" + kinds)
    p.add_argument("campaign", help="campaign TOML file")
    p.add_argument("--out", help="store path (default: CAMPAIGN_NAME.zarr here)")
    p.add_argument("--set", action="append", default=[], metavar="dotted.key=value",
                   help="override a campaign field (TOML value), repeatable")
    p.add_argument("--workers", type=int, default=None,
                   help="local dask worker processes, or SLURM jobs; 0 runs in this "
                        "process without dask (default: in this process for jobs below "
                        "2e10 vertex-image tests, else one worker per CPU; see "
                        "ideas_hpc/engine/job_cluster.py)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="use an existing dask scheduler (tcp://host:8786)")
    p.add_argument("--cluster", choices=("local", "slurm"), default="local",
                   help="start a local cluster (default) or SLURM jobs via dask-jobqueue")
    p.add_argument("--slurm-config", default=None,
                   help="dask-jobqueue config file for --cluster slurm (default: dask.config "
                        "jobqueue.slurm, i.e. the package's jobqueue.yaml under your dask config)")
    p.add_argument("--device", choices=("cpu", "cuda"), default=None,
                   help="where the closed-loop attitude flights run (default: the "
                        "campaign's run.device, cpu); cuda needs numba.cuda.is_available()")
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted store (skips finished chunks)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(handler=_cmd_run)

    r = sub.add_parser("report", help="write figures and a text summary of a store",
                       description="Write the figures that apply to a store (PNG) and a text "
                                   "summary (summary.txt, also printed): body, design, "
                                   "target/threshold/reached, verification verdict. A store "
                                   "with unfinished chunks is refused.")
    r.add_argument("store", help="zarr store written by 'ideas-hpc run'")
    r.add_argument("--out", default=None, help="output folder (default: STORE-report)")
    r.add_argument("--html", action="store_true",
                   help="also write report.html: one self-contained interactive page (3-D "
                        "body coloured by the per-vertex result, ring and swarm, trade "
                        "curves, verification distribution); opens offline")
    r.set_defaults(handler=_cmd_report)

    s = sub.add_parser("scan-arrival", help="coverage with lighting versus arrival epoch",
                       description="Fly a flyby or monte-carlo campaign's swarm once and run "
                                   "the quality pass for N arrival epochs (Sun from the "
                                   "ephemeris) over one rotation period.")
    s.add_argument("campaign", help="campaign TOML file")
    s.add_argument("--n", type=int, default=24, help="number of epochs (default 24)")
    s.add_argument("--span-h", type=float, default=None,
                   help="hours scanned from flyby.epoch_s (default: one rotation period)")
    s.add_argument("--set", action="append", default=[], metavar="dotted.key=value",
                   help="override a campaign field (TOML value), repeatable")
    s.add_argument("--out", default=None, help="write the scan to this netCDF file")
    s.set_defaults(handler=_cmd_scan)

    e = sub.add_parser("scan-encounter", help="coverage versus approach declination and phase",
                       description="Fly an encounter campaign's ring (and swarm) for a grid of "
                                   "approach declinations and phase angles.")
    e.add_argument("campaign", help="campaign TOML file with flyby.geometry = \"encounter\"")
    e.add_argument("--dec-deg", type=float, nargs="+", default=None,
                   help="approach declinations from the equator (default -60 -30 0 30 60 90)")
    e.add_argument("--phase-deg", type=float, nargs="+", default=None,
                   help="phase angles (default 30 60 90 120)")
    e.add_argument("--step-deg", type=float, default=10.0,
                   help="swarm-angle step of the ring's candidates (default 10)")
    e.add_argument("--set", action="append", default=[], metavar="dotted.key=value",
                   help="override a campaign field (TOML value), repeatable")
    e.add_argument("--out", default=None, help="write the scan to this netCDF file")
    e.add_argument("--plot", default=None, help="write the coverage map to this PNG")
    e.set_defaults(handler=_cmd_scan_encounter)

    from ideas_hpc.campaign.body_report import add_body_command
    from ideas_hpc.export.kernels import add_export_command
    from ideas_hpc.campaign.validate_store import add_validate_command
    from ideas_hpc.campaign.study_command import add_study_command
    add_body_command(sub)
    add_export_command(sub)
    add_validate_command(sub)
    add_study_command(sub)
    from ideas_hpc.campaign.resolution_study import EROS_MODELS

    v = sub.add_parser("resolution", help="one design campaign on several shape models",
                       description="Run a design campaign once per shape model (body.name "
                                   "set to each) and print N, coverage and P side by side "
                                   "with the meshes' vertex areas; a requirement is resolved "
                                   "when N is the same on every model (docs/requirement.md). "
                                   "Each model's store is resumable.")
    v.add_argument("campaign", help="design campaign TOML file")
    v.add_argument("--shapes", default=",".join(EROS_MODELS),
                   help="comma-separated shape models (default: the four Eros models, "
                        "coarse to fine)")
    v.add_argument("--set", action="append", default=[], metavar="dotted.key=value",
                   help="override a campaign field (TOML value), repeatable")
    v.add_argument("--out", default=None,
                   help="folder of the stores and resolution.csv (default: STEM-resolution)")
    v.add_argument("--workers", type=int, default=None, help="as for 'run'")
    v.add_argument("--eps-tol", default=None, metavar="PCT,PCT,...",
                   help="also the N of these tolerances (percent), read from each store's "
                        "coverage-versus-N curve")
    v.add_argument("--no-progress", action="store_true", help="no progress bar")
    v.set_defaults(handler=_cmd_resolution)
