"""``dolfinx-friction run|check|sweep|plot|render``: the one front end of the command line
(scene-format.md).

One parser; one handling of errors: one line on stderr (from rank 0), the exit status of
:mod:`~dolfinx_friction.cli.exits` (``--debug`` lets every exception through, with its
traceback); one signal handler (:mod:`~dolfinx_friction.cli.signals`); the MPI launcher read
in one place (:mod:`~dolfinx_friction.cli.mpi`), numpy's settings set before it starts
(:mod:`~dolfinx_friction.cli.environment`).  The commands themselves:
:mod:`~dolfinx_friction.cli.commands`.
"""
from __future__ import annotations

import argparse
import logging
import math
import signal
import warnings
from pathlib import Path
from typing import Optional, Sequence

from dolfinx_friction import __version__
from dolfinx_friction.cli import commands, environment, mpi, signals
from dolfinx_friction.cli.exits import EXIT_INPUT, EXIT_INTERNAL, classify, error, signal_status
from dolfinx_friction.errors import Interrupted
from dolfinx_friction.scene.workspace import Workspace

__all__ = ["main"]


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # one line (from rank 0), no usage dump
        error(message)
        raise SystemExit(EXIT_INPUT)


def _at_least_one(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, not {value}")
    return value


def _scale(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a positive number, not {text}")
    return value


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="dolfinx-friction",
                     description="Node-to-surface penalty contact with Coulomb friction "
                                 "(CalculiX scheme) on Gmsh scenes, solved with DOLFINx/PETSc.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of errors")
    parser.add_argument("--version", action="version", version=f"dolfinx-friction {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    hidden = dict(action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    run = sub.add_parser("run", help="solve a scene and write its results")
    run.add_argument("scene", type=Path)
    run.add_argument("--out", type=Path, help="output directory (overrides [output] dir)")
    run.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene value by dotted path, e.g. contact.0.mu=0.2")
    run.add_argument("--quiet", action="store_true", help="no progress output")
    run.add_argument("--debug", **hidden)
    check = sub.add_parser("check", help="validate a scene and its mesh, solve nothing")
    check.add_argument("scene", type=Path)
    check.add_argument("--set", dest="overrides", action="append", default=[],
                       metavar="KEY=VALUE")
    check.add_argument("--debug", **hidden)
    sweep = sub.add_parser(
        "sweep", help="run a scene at every point of a cartesian product of --set values",
        description="Run SCENE at every point of the cartesian product of the --set values, "
                    "each point in DIR/<key=value,...>/, up to -j at a time, and write "
                    "DIR/sweep.csv (one row per point: the values, converged or not, "
                    "increments, Newton iterations, wall time, final reactions, the reason "
                    "of a failure).  Exit 0 when every point converged, 3 otherwise.")
    sweep.add_argument("scene", type=Path)
    sweep.add_argument("--set", dest="sweeps", action="append", default=[],
                       metavar="KEY=V1,V2,...",
                       help="values of one scene key (dotted path, as run --set); the list is "
                            "split at commas outside brackets, braces and quotes: "
                            "step.1.bc.0.u=[0,0,-1],[0,0,-2] is two values")
    sweep.add_argument("-j", "--jobs", type=_at_least_one, default=None, metavar="N",
                       help="points run at the same time (default: the number of cores)")
    sweep.add_argument("--out", type=Path, metavar="DIR",
                       help="sweep folder (default: <scene stem>_sweep next to the scene)")
    sweep.add_argument("--quiet", action="store_true", help="no line per finished point")
    sweep.add_argument("--debug", **hidden)
    plot = sub.add_parser(
        "plot", help="charts of a results folder (history.csv) or a sweep folder (sweep.csv)",
        description="Charts with matplotlib: of a run (reactions against the pseudo-time t, "
                    "Newton iterations per increment, slave nodes in contact and slipping) "
                    "or of a sweep (final reactions against each swept value).")
    plot.add_argument("directory", type=Path, metavar="RESULTS_DIR")
    plot.add_argument("-o", "--output", type=Path, metavar="FILE",
                      help="picture file, format from its suffix (default: RESULTS_DIR/"
                           "history.png, or sweep.png for a sweep folder)")
    plot.add_argument("--debug", **hidden)
    render = sub.add_parser(
        "render", help="picture of one converged increment from the files of a run",
        description="The picture of dolfinx_friction.viz.pictures.render (deformed bodies, contact "
                    "surfaces coloured by contact pressure or stick/slip status) from the "
                    "field files that a run wrote (output.fields = true).")
    render.add_argument("directory", type=Path, metavar="RESULTS_DIR")
    render.add_argument("--increment", type=int, metavar="N",
                        help="the N-th converged increment, counted from 1 in the order of "
                             "history.csv over all steps (negative: from the end; default: "
                             "the last)")
    render.add_argument("-o", "--output", type=Path, metavar="FILE.png",
                        help="default: RESULTS_DIR/render_step<s>_increment<iiii>.png")
    render.add_argument("--scalar", choices=("pressure", "status"), default="pressure",
                        help="colour of the contact surfaces (default: pressure)")
    render.add_argument("--warp", type=_scale, default=1.0,
                        help="scale of the displacements (default 1)")
    render.add_argument("--amplify", choices=("total", "deformation"), default="total",
                        help="what --warp scales: the whole displacement (default) or only "
                             "what differs from each body's mean translation")
    render.add_argument("--von-mises", action="store_true",
                        help="colour the bodies by their von Mises stress")
    render.add_argument("--debug", **hidden)
    return parser


def _quiet_libraries(debug: bool) -> None:
    """Library log records reach stderr from WARNING up; with --debug INFO too, with the
    form compiler's command lines (which the package drops otherwise: see
    :mod:`dolfinx_friction`), and numpy's floating-point RuntimeWarnings.

    The handler is installed before dolfinx is imported, so that FFCx's
    ``logging.basicConfig()`` adds none of its own.
    """
    if not debug:  # numpy's floating-point chatter: the failure it means is reported
        warnings.filterwarnings("ignore", category=RuntimeWarning,
                                message=r"(overflow|invalid value|divide by zero|underflow) "
                                        r"encountered")
    else:
        logging.getLogger("dolfinx_friction").setLevel(logging.DEBUG)
    root = logging.getLogger()
    if root.handlers:  # configured by an embedding program: leave it alone
        return
    handler = logging.StreamHandler()
    handler.setLevel(logging.INFO if debug else logging.WARNING)
    handler.setFormatter(logging.Formatter("%(levelname)s:%(name)s:%(message)s"))
    root.addHandler(handler)


class _NoticeFormatter(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        text = record.getMessage()
        return text if record.levelno < logging.WARNING else \
            f"dolfinx-friction: {record.levelname.lower()}: {text}"


def _show_notices(quiet: bool) -> None:
    """The package's log records as the command line's lines on stderr (the library logs
    from rank 0 only): warnings as "dolfinx-friction: warning: ...", notices (a rerun
    replacing results) as they are, unless ``--quiet``."""
    logger = logging.getLogger("dolfinx_friction")
    for old in [h for h in logger.handlers if isinstance(h.formatter, _NoticeFormatter)]:
        logger.removeHandler(old)  # main() called again in this process
    handler = logging.StreamHandler()
    handler.setLevel(logging.WARNING if quiet else min(logging.INFO, logger.level or logging.INFO))
    handler.setFormatter(_NoticeFormatter())
    logger.addHandler(handler)
    logger.setLevel(min(logger.level or logging.INFO, logging.INFO))  # (--debug: DEBUG)
    logger.propagate = False


def main(argv: Optional[Sequence[str]] = None, workspace: Optional[Workspace] = None) -> int:
    """Run the command line ``argv`` (default: ``sys.argv[1:]``); the exit status.
    ``workspace``: what a ``run`` keeps for the next one in this process (a sweep's
    worker, :mod:`~dolfinx_friction.cli.worker`)."""
    environment.prepare()  # before anything imports numpy
    args = _parser().parse_args(argv)
    args.workspace = workspace
    _quiet_libraries(args.debug)
    _show_notices(getattr(args, "quiet", False))
    interruption = signals.install(args.command, mpi.rank())
    try:
        status = commands.COMMANDS[args.command](args, interruption)
    except (Interrupted, KeyboardInterrupt) as exc:  # (the line of a run: said already)
        return signal_status(interruption.stopped(getattr(exc, "code", signal.SIGINT)))
    except Exception as exc:
        if args.debug:
            raise
        status, message = classify(exc)
        if status is None:
            status = EXIT_INTERNAL
            message = (f"internal error: {type(exc).__name__}: {message} "
                       "(rerun with --debug for the traceback)")
        error(message)
        return status
    if interruption.announced:  # a signal after the last checkpoint: as the line said
        return signal_status(interruption.stopped(0))
    return status


if __name__ == "__main__":
    raise SystemExit(main())
