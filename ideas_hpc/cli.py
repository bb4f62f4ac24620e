"""``ideas-hpc`` command line: ``size``, ``run``, ``report``, ``scan-arrival``, ``resolution``...

Bad input (an :class:`~ideas_hpc.base.errors.InputError`) prints one line naming
the problem and exits with status 2; no traceback. SIGINT and SIGTERM print one
line and exit with 128 + the signal number (130, 143); stores stay resumable.
"""

from __future__ import annotations

import argparse
import signal
import sys
from contextlib import contextmanager

from ideas_hpc import __version__
from ideas_hpc.base.errors import InputError
from ideas_hpc.base.units import CM, DEG, KM, UM



def _add_size(sub) -> None:
    p = sub.add_parser("size", help="print the instrument and flyby sizing (paper Tables 3-4)",
                       description="Size the camera and the ring flyby for a body (SPEC section 2). "
                                   "Lengths in km, angles in deg.")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--body", default="eros",
                   help="body name (eros, eros001708, ellipsoid, sphere...) or shape file path "
                        "(default: eros)")
    g.add_argument("--r-av", type=float, metavar="KM", help="given mean radius, km")
    g.add_argument("--paper", action="store_true",
                   help="use the paper's R_max/R_min (17.670/3.222 km) to reproduce its tables")
    from ideas_hpc.base.instrument import INSTRUMENT_DEFAULTS as cam

    p.add_argument("--resolution", type=float, default=cam["ground_resolution_m"], metavar="M",
                   help=f"ground resolution X, m (default {cam['ground_resolution_m']:g})")
    p.add_argument("--aperture", type=float, default=cam["aperture_cm"], metavar="CM",
                   help=f"aperture diameter D, cm (default {cam['aperture_cm']:g})")
    p.add_argument("--wavelength", type=float, default=cam["wavelength_um"], metavar="UM",
                   help=f"imaging wavelength, um (default {cam['wavelength_um']:g})")
    p.add_argument("--elevation", type=float, default=cam["min_elevation_deg"], metavar="DEG",
                   help=f"minimum elevation angle, deg (default {cam['min_elevation_deg']:g})")
    p.add_argument("--data-path", default=None, help="folder with shape models "
                   "(searched before $IDEAS_HPC_DATA)")


def _cmd_size(args) -> int:
    from ideas_hpc.body.bodies import load_body
    from ideas_hpc.flyby.sizing import PAPER_R_MAX, PAPER_R_MIN, format_table, size_flyby

    inst = dict(ground_resolution=args.resolution, aperture=args.aperture * CM,
                wavelength=args.wavelength * UM, min_elevation=args.elevation * DEG)
    paper = size_flyby(r_max=PAPER_R_MAX, r_min=PAPER_R_MIN, **inst)
    if args.paper:
        print(format_table(paper, "Sizing from the paper's R_max 17.670 km, R_min 3.222 km"))
        return 0
    if args.r_av is not None:
        if not args.r_av > 0:
            raise InputError(f"must be > 0 km, got {args.r_av:g}", field="--r-av")
        s = size_flyby(r_av=args.r_av * KM, **inst)
        print(format_table(s, f"Sizing for a given mean radius R_av = {args.r_av:g} km", paper))
        return 0
    body = load_body(args.body, data_path=args.data_path)
    print(f"body: {body.note}")
    print(f"shape: {body.shape.summary()}")
    s = size_flyby(r_max=body.shape.r_max, r_min=body.shape.r_min, **inst)
    print(format_table(s, f"Sizing for {body.name}", paper))
    return 0


class Stopped(KeyboardInterrupt):
    """SIGTERM, raised where Python code runs so ``with`` blocks clean up as for Ctrl-C."""

    signal_name = "SIGTERM"
    signal_number = int(signal.SIGTERM)


@contextmanager
def stop_signals():
    """SIGTERM raises :class:`Stopped` in the main thread while the block runs."""
    def _raise(signum, frame):
        raise Stopped()

    try:
        old = signal.signal(signal.SIGTERM, _raise)
    except ValueError:                 # not the main thread (e.g. called from a test)
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ideas-hpc",
        description="Design spacecraft swarms that map a small body in one flyby: size the "
                    "camera and flyby, run a campaign file into a zarr store, report on it.",
        epilog="Run 'ideas-hpc COMMAND --help' for the options of one command.")
    parser.add_argument("--version", action="version", version=f"ideas_hpc {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    _add_size(sub)
    try:
        from ideas_hpc.commands import add_commands  # run / report, when present
    except ImportError:
        add_commands = None
    if add_commands is not None:
        add_commands(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    handler = {"size": _cmd_size}.get(args.command) or getattr(args, "handler", None)
    try:
        with stop_signals():
            return int(handler(args) or 0)
    except InputError as exc:
        print(f"ideas-hpc: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        # one line, whatever was running: stores are written atomically or per
        # finished chunk and their locks released on the way out, so --resume goes on
        name = getattr(exc, "signal_name", "SIGINT")
        again = " (rerun with --resume to continue)" if args.command == "run" else ""
        print(f"ideas-hpc: stopped by {name}{again}", file=sys.stderr)
        return 128 + getattr(exc, "signal_number", signal.SIGINT)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
