"""The ``ideas-hpc study`` command line (:mod:`ideas_hpc.campaign.study`; docs/study.md)."""

from __future__ import annotations

from ideas_hpc.campaign.study import ANSWERS, DEFAULT_ANSWERS, StudyOptions, run_study


def _cmd_study(args) -> int:
    from ideas_hpc.base import progress

    from ideas_hpc.campaign.study_distance import km_list, parse_km

    answers = tuple(a.strip() for a in (args.answers or ",".join(DEFAULT_ANSWERS)).split(",")
                    if a.strip())
    distances = ()
    if args.ca_distances_km is not None:
        distances = parse_km(args.ca_distances_km)
        if args.answers is None:        # a list given: its answer runs with the defaults
            answers += ("distance",)
    opts = StudyOptions(sigmas_m=km_list(args.bplane_sigmas_km, "--bplane-sigmas-km"), worlds=args.worlds,
                        per_world=args.per_world, answers=answers, force=args.force,
                        time_limit_s=args.time_limit_s, distances_m=distances)
    with progress.enabled(not args.no_progress):
        run_study(args.store, opts)
    return 0


def add_study_command(sub) -> None:
    p = sub.add_parser("study", help="answers of a design under a target prior: the price "
                                     "of ignorance, the value of a late navigation update, "
                                     "per-target reliability",
                       description="Reruns the design's bank and search on variants of the "
                                   "store's campaign (the known nominal body; scaled B-plane "
                                   "errors) and flies the designed swarm through nested draws "
                                   "(worlds outer, navigation, dispersions and failures inner); "
                                   "writes each answer into the store (groups study_*) and "
                                   "prints one line per answer (docs/study.md).")
    p.add_argument("store", help="store of a design-nadir run with design.success_probability")
    p.add_argument("--bplane-sigmas-km", default="100,30,10,3",
                   help="B-plane 1-sigma semi-major axes, km, the ellipse and TCA sigma "
                        "scaled in proportion (default 100,30,10,3; the campaign's is added)")
    p.add_argument("--worlds", type=int, default=20, help="outer target worlds M (default 20)")
    p.add_argument("--per-world", type=int, default=10,
                   help="inner draws K per world (default 10)")
    p.add_argument("--ca-distances-km", default=None,
                   help="closest-approach distances d_sep, km, comma-separated (e.g. "
                        "100,157,300; the store's is added): the fewest N, its P, the GSD "
                        "and the LOS rate at each, the same seeds (adds the distance answer)")
    p.add_argument("--answers", default=None,
                   help=f"which answers, comma-separated, of {','.join(ANSWERS)} (default "
                        f"{','.join(DEFAULT_ANSWERS)}, and distance with --ca-distances-km)")
    p.add_argument("--time-limit-s", type=float, default=None,
                   help="seconds for each fewest-N search (default: the campaign's "
                        "design.time_limit_s); a search stopped by it says so")
    p.add_argument("--force", action="store_true",
                   help="recompute answers already stored with the same options")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(handler=_cmd_study)
