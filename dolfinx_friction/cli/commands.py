"""``dolfinx-friction sweep | plot | render``: studies of a scene and pictures of written
results.  Each runs in one process (``sweep`` starts its own runs): under ``mpirun`` with
more than one rank they refuse with one line.  Bad input: one line on stderr, exit 2.
"""
from __future__ import annotations

import argparse
import math
import os
import signal
import sys
import threading
from pathlib import Path

from dolfinx_friction.errors import (EXIT_DIVERGED, EXIT_INPUT, EXIT_INTERNAL, EXIT_SIGNAL,
                                     Interrupted)

__all__ = ["COMMANDS", "add_parsers", "main"]

COMMANDS = ("sweep", "plot", "render")
#: Environment variables that MPI launchers set to the number of ranks.
_MPI_SIZES = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "MPI_LOCALNRANKS", "MV2_COMM_WORLD_SIZE")


class _UsageError(ValueError):
    """A command used where or how it cannot work (one line, exit 2)."""


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


def add_parsers(sub) -> None:
    """The three subcommands, on the subparsers of ``dolfinx-friction``."""
    hidden = dict(action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
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
    sweep.add_argument("-j", "--jobs", type=_at_least_one, default=1, metavar="N",
                       help="points run at the same time (default 1)")
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


def _error(message: str) -> None:
    print(f"dolfinx-friction: error: {message}", file=sys.stderr, flush=True)


def _mpi_ranks() -> int:
    for name in _MPI_SIZES:
        if os.environ.get(name, "").isdigit():
            return int(os.environ[name])
    return 1


def _interrupt(signum: int, frame) -> None:
    """SIGINT / SIGTERM: the sweep stops its running points and ends (130 / 143)."""
    raise Interrupted(signum)


def _sweep(args) -> int:
    from dolfinx_friction.io.files import file_fault
    from dolfinx_friction.scene.toml import SceneError
    from dolfinx_friction.cli.sweep import SWEEP_CSV, default_sweep_dir, plan, run_sweep
    reason = file_fault(args.scene)
    if reason is not None:
        raise SceneError(f"{args.scene}: "
                         f"{'no such scene file' if reason == 'no such file' else reason}")
    points = plan(args.scene, args.sweeps)
    directory = args.out if args.out is not None else default_sweep_dir(args.scene)
    if directory.exists() and not directory.is_dir():
        raise _UsageError(f"sweep folder {directory}: not a folder")
    table = directory / SWEEP_CSV
    ended: list = []

    def report(result, row) -> None:
        ended.append(result)
        if args.quiet:
            return
        state = (f"converged, {row.get('increments')} increments, "
                 f"{row.get('newton_iterations')} Newton iterations" if row["converged"] ==
                 "true" else f"failed: {result.reason}")
        print(f"[{len(ended)}/{len(points)}] {result.point.label}: {state} "
              f"({result.wall:.1f} s)", flush=True)

    if threading.current_thread() is threading.main_thread():  # (even where SIG_IGN came in)
        for signum in (signal.SIGINT, signal.SIGTERM):
            signal.signal(signum, _interrupt)
    try:
        results = run_sweep(args.scene, points, directory, args.jobs, report)
    except (KeyboardInterrupt, Interrupted) as exc:
        _error(f"sweep interrupted: {len(ended)} of {len(points)} points ended"
               + (f", listed in {table}" if ended else ""))
        return EXIT_SIGNAL[getattr(exc, "signum", signal.SIGINT)]
    failed = [r for r in results if r.status != 0]
    if not args.quiet:
        print(f"sweep: {len(points)} points, {len(points) - len(failed)} converged, "
              f"{len(failed)} failed; table {table}")
    if failed:
        _error(f"{len(failed)} of {len(points)} points failed (see the reason column of "
               f"{table})")
        return EXIT_DIVERGED
    return 0


def _incomplete(run, what: str) -> int:
    """Exit status of a picture made: 2 (and the line) for a run killed half-way."""
    if run.complete:
        return 0
    _error(f"{run.directory}: the run is incomplete (history.csv but no summary.json): "
           f"{what}")
    return EXIT_INPUT


def _plot(args) -> int:
    from dolfinx_friction.viz.plots import plot_history, plot_sweep
    from dolfinx_friction.io.reader import read_run
    directory = args.directory
    if (directory / "sweep.csv").is_file():
        path, _ = plot_sweep(directory, args.output or directory / "sweep.png")
        print(f"chart: {path}")
        return 0
    run = read_run(directory)
    path = plot_history(run, args.output or directory / "history.png")
    print(f"chart: {path}")
    return _incomplete(run, f"drew its {len(run.history)} converged increments into {path}")


def _render(args) -> int:
    if args.output is not None and args.output.suffix.lower() != ".png":
        raise _UsageError(f"-o {args.output}: render writes PNG files (FILE.png)")
    from dolfinx_friction.viz.snapshot import render_files
    path, run, row = render_files(args.directory, args.output, args.increment,
                                  scalar="status" if args.scalar == "status"
                                  else "contact_pressure", warp=args.warp,
                                  amplify=args.amplify,
                                  body_scalar="von_mises" if args.von_mises else None)
    print(f"picture: {path}")
    return _incomplete(run, f"drew converged increment {row + 1} of {len(run.history)} "
                            f"into {path}")


def main(args) -> int:
    """Run one of :data:`COMMANDS`; the exit status."""
    from dolfinx_friction.io.reader import ResultsError
    from dolfinx_friction.scene.toml import SceneError
    from dolfinx_friction.cli.sweep import SweepError
    try:
        if _mpi_ranks() > 1:
            raise _UsageError(f"{args.command} runs in one process (a sweep starts its own "
                              "runs): start it without mpirun")
        return {"sweep": _sweep, "plot": _plot, "render": _render}[args.command](args)
    except KeyboardInterrupt:
        _error(f"{args.command} interrupted")
        return EXIT_SIGNAL[signal.SIGINT]
    except (_UsageError, SweepError, ResultsError, SceneError) as exc:
        _error(" ".join(str(exc).split()))
        return EXIT_INPUT
    except OSError as exc:
        _error(f"{exc.filename}: {exc.strerror}" if exc.filename and exc.strerror else str(exc))
        return EXIT_INPUT
    except Exception as exc:
        if args.debug:
            raise
        _error(f"internal error: {type(exc).__name__}: {' '.join(str(exc).split())} "
               "(rerun with --debug for the traceback)")
        return EXIT_INTERNAL
