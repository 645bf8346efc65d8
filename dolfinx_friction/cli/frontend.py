"""``dolfinx-friction run|check|sweep|plot|render``: the command line of scene-format.md
(sweep, plot and render: :mod:`dolfinx_friction.cli.commands`)."""
from __future__ import annotations

import _thread
import argparse
import logging
import os
import signal
import sys
import threading
import warnings
from pathlib import Path
from typing import Optional, Sequence

from dolfinx_friction import __version__

from dolfinx_friction.cli import commands
from dolfinx_friction.errors import (EXIT_INPUT, EXIT_INTERNAL, EXIT_SIGNAL, Interrupted,
                                     OutputError, classify, interruption)
from dolfinx_friction.io.files import file_fault
from dolfinx_friction.scene.toml import SceneError, default_output_dir, load_scene


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # one line (from rank 0), no usage dump
        if _rank() == 0:
            print(f"dolfinx-friction: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_INPUT)


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="dolfinx-friction",
                     description="Node-to-surface penalty contact with Coulomb friction "
                                 "(CalculiX scheme) on Gmsh scenes, solved with DOLFINx/PETSc.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of errors")
    parser.add_argument("--version", action="version", version=f"dolfinx-friction {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    run = sub.add_parser("run", help="solve a scene and write its results")
    run.add_argument("scene", type=Path)
    run.add_argument("--out", type=Path, help="output directory (overrides [output] dir)")
    run.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene value by dotted path, e.g. contact.0.mu=0.2")
    run.add_argument("--quiet", action="store_true", help="no progress output")
    run.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                     help=argparse.SUPPRESS)
    check = sub.add_parser("check", help="validate a scene and its mesh, solve nothing")
    check.add_argument("scene", type=Path)
    check.add_argument("--set", dest="overrides", action="append", default=[],
                       metavar="KEY=VALUE")
    check.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                       help=argparse.SUPPRESS)
    commands.add_parsers(sub)  # sweep, plot, render
    return parser


def _precheck(args, scene) -> None:
    """What can be told before dolfinx is imported and the mesh is read: the mesh file
    exists, and no regular file stands where the output directory is to be made."""
    mesh = Path(scene.mesh)
    reason = file_fault(mesh)
    if reason is not None:
        raise SceneError(f"mesh.file: {mesh}: {reason}", key="mesh.file", source=str(args.scene))
    if args.command != "run":
        return
    directory = Path(args.out) if args.out is not None else default_output_dir(scene)
    for path in (directory, *directory.absolute().parents):
        if path.exists():
            if not path.is_dir():
                raise OutputError(f"output directory {directory}: {path} is not a directory")
            if not os.access(path, os.W_OK | os.X_OK):
                raise OutputError(f"output directory {directory}: {path} is not writable")
            break


def _check(args, scene) -> None:
    """The scene and everything it asks of its mesh (:class:`~dolfinx_friction.scene.build.
    DiscreteScene`); no forms, nothing solved."""
    from mpi4py import MPI
    from dolfinx_friction.scene.build import DiscreteScene
    problem = DiscreteScene(scene, MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank == 0:
        n_dofs = problem.layout.n_global * problem.gdim
        print(f"{args.scene}: ok ({problem.gdim}D, {len(scene.bodies)} bodies, "
              f"{len(scene.contacts)} contact pairs, {len(scene.steps)} steps, {n_dofs} dofs)")


def _run(args, scene) -> None:
    from mpi4py import MPI
    from dolfinx_friction.scene.runner import run
    from dolfinx_friction.cli.progress import Progress
    progress = Progress() if MPI.COMM_WORLD.rank == 0 and not args.quiet else None
    try:
        result = run(scene, out=args.out, progress=progress)
    finally:
        if progress is not None:
            progress.close()
    if MPI.COMM_WORLD.rank == 0 and not args.quiet:
        s = result.summary
        print(f"done: {s.increments} increments, {s.newton_iterations} Newton iterations, "
              f"{s.cutbacks} cutbacks, {s.wall:.2f} s; results in {result.directory}")


#: what MPI launchers (Open MPI, PMIx, MPICH, MVAPICH) set in each rank's environment
_RANK_VARIABLES = ("OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK", "MV2_COMM_WORLD_RANK")


def _rank() -> int:
    """This process's MPI rank, without initialising MPI just to print an error."""
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is not None and mpi.Is_initialized() and not mpi.Is_finalized():
        return mpi.COMM_WORLD.rank
    for name in _RANK_VARIABLES:
        if os.environ.get(name, "").isdigit():
            return int(os.environ[name])
    return 0


def _no_singleton_daemon() -> None:
    """A run started without a launcher is an MPI singleton, for which Open MPI 4 starts a
    daemon (orted) that only spawning processes needs (the package never spawns): ~0.3 s of
    wall time at start-up (``benchmarks/bench_small.py``).  Ask for none, before mpi4py is
    imported; under a launcher (its rank variables set) nothing changes.  Open MPI 5 does
    not know the variable and ignores it, as it ignores every unknown ``OMPI_MCA_``."""
    if not any(name in os.environ for name in _RANK_VARIABLES):
        os.environ.setdefault("OMPI_MCA_ess_singleton_isolated", "1")


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
    handler.setLevel(logging.WARNING if quiet else logging.INFO)
    handler.setFormatter(_NoticeFormatter())
    logger.addHandler(handler)
    logger.setLevel(min(logger.level or logging.INFO, logging.INFO))  # (--debug: DEBUG)
    logger.propagate = False


def _on_signal(signum: int, frame) -> None:
    """SIGINT / SIGTERM: one line (rank 0), then stop where it is safe (see
    :class:`~dolfinx_friction.errors.Interruption`); exit 130 / 143."""
    state = interruption
    if state.signum is not None:  # already stopping (a second Ctrl-C, or SIGTERM after it)
        return
    state.signum = signum
    state.announce()
    if not (state.solving or state.writing):
        raise Interrupted(signum)


def _watch_signals(signals: set) -> None:
    """A thread that takes SIGINT / SIGTERM (blocked in every other thread), prints the line
    at once and hands the signal to the main thread's handler.

    Python runs a signal handler in the main thread only between bytecodes: not while the
    main thread waits in MPI, fsync or HDF5.  Under ``mpirun`` that is too late: Open MPI
    sends the ranks SIGTERM and kills them one second later (``odls_base_sigkill_timeout``).
    This thread needs only the GIL, which such waits release."""
    while True:
        signum = signal.sigwait(signals)
        interruption.received = interruption.received or signum
        interruption.announce()  # (once: a second Ctrl-C says nothing more)
        _thread.interrupt_main(signum)  # runs _on_signal in the main thread


def _install_signal_handlers() -> None:
    if interruption.armed or threading.current_thread() is not threading.main_thread():
        return  # done already, or main() called from a thread (signals are the caller's)
    interruption.armed = True
    interruption.rank = _rank()  # before MPI starts: from the launcher's environment
    signals = {signal.SIGINT, signal.SIGTERM}
    for signum in signals:
        signal.signal(signum, _on_signal)
    signal.pthread_sigmask(signal.SIG_BLOCK, signals)  # inherited by threads started later
    threading.Thread(target=_watch_signals, args=(signals,), daemon=True,
                     name="dolfinx-friction-signals").start()


def main(argv: Optional[Sequence[str]] = None) -> int:
    args = _parser().parse_args(argv)
    _quiet_libraries(args.debug)
    if args.command in commands.COMMANDS:
        return commands.main(args)
    _show_notices(getattr(args, "quiet", False))
    _no_singleton_daemon()
    _install_signal_handlers()
    try:
        reason = file_fault(args.scene)
        if reason is not None:
            raise SceneError(f"{args.scene}: "
                             f"{'no such scene file' if reason == 'no such file' else reason}")
        # The scene is read and validated before dolfinx is imported: a bad scene is
        # answered at once.
        scene = load_scene(args.scene, args.overrides)
        _precheck(args, scene)
        _run(args, scene) if args.command == "run" else _check(args, scene)
    except Interrupted as exc:  # the line was printed when the signal came
        return EXIT_SIGNAL.get(exc.signum, 128 + exc.signum)
    except Exception as exc:  # one line on stderr (rank 0), a traceback only with --debug
        if args.debug:
            raise
        status, message = classify(exc)
        if status is None:
            status = EXIT_INTERNAL
            message = (f"internal error: {type(exc).__name__}: {message} "
                       "(rerun with --debug for the traceback)")
        if _rank() == 0:
            print(f"dolfinx-friction: error: {message}", file=sys.stderr, flush=True)
        return status
    if interruption.announced:  # a signal came after the last checkpoint: say what was said
        # the main thread may finish before the handler ran: the signal thread's signal
        # counts, and the late handler then finds the run already stopping
        interruption.signum = interruption.signum or interruption.received
        return EXIT_SIGNAL.get(interruption.signum, 128 + interruption.signum)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
