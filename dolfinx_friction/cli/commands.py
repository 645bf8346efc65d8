"""The bodies of the commands of :mod:`~dolfinx_friction.cli.frontend`.

Each takes the parsed arguments and the command's
:class:`~dolfinx_friction.cli.signals.Interruption` and returns the exit status; what goes
wrong goes up as an exception, which the front end turns into one line and a status
(:mod:`~dolfinx_friction.cli.exits`).  ``run`` and ``check`` read and validate the scene
before dolfinx is imported (a bad scene is answered at once); ``sweep``, ``plot`` and
``render`` run in one process (``sweep`` starts its own runs) and refuse ``mpirun``.
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from dolfinx_friction.cli import mpi
from dolfinx_friction.cli.exits import EXIT_DIVERGED, EXIT_INPUT, EXIT_OK, error, signal_status
from dolfinx_friction.cli.signals import Interruption
from dolfinx_friction.errors import Interrupted, OutputError
from dolfinx_friction.io.files import file_fault
from dolfinx_friction.scene.toml import SceneError, default_output_dir, load_scene
from dolfinx_friction.scene.validation import check_mesh_file

if TYPE_CHECKING:
    from dolfinx_friction.cli.sweep import Point, WorkerPool

__all__ = ["COMMANDS", "UsageError"]


class UsageError(ValueError):
    """A command used where or how it cannot work (one line, exit 2)."""


def _scene_file(path: Path) -> None:
    reason = file_fault(path)
    if reason is not None:
        raise SceneError(f"{path}: {'no such scene file' if reason == 'no such file' else reason}")


def _scene(args: argparse.Namespace):
    """The scene of ``run`` / ``check``, with what can be told before dolfinx is imported
    and the mesh is read: the mesh file exists, and (``run``) no regular file stands where
    the output directory is to be made."""
    _scene_file(args.scene)
    scene = load_scene(args.scene, args.overrides)
    check_mesh_file(scene, args.scene)
    if args.command == "run":
        directory = Path(args.out) if args.out is not None else default_output_dir(scene)
        for path in (directory, *directory.absolute().parents):
            if path.exists():
                if not path.is_dir():
                    raise OutputError(f"output directory {directory}: {path} is not a directory")
                if not os.access(path, os.W_OK | os.X_OK):
                    raise OutputError(f"output directory {directory}: {path} is not writable")
                break
    return scene


def run(args: argparse.Namespace, interruption: Interruption) -> int:
    scene = _scene(args)
    MPI = mpi.start()

    from dolfinx_friction.cli.progress import Progress
    from dolfinx_friction.scene.runner import run as run_scene
    progress = Progress() if MPI.COMM_WORLD.rank == 0 and not args.quiet else None
    try:
        result = run_scene(scene, out=args.out, progress=progress, control=interruption,
                           workspace=args.workspace)
    finally:
        interruption.end()
        if progress is not None:
            progress.close()
    if MPI.COMM_WORLD.rank == 0 and not args.quiet:
        s = result.summary
        print(f"done: {s.increments} increments, {s.newton_iterations} Newton iterations, "
              f"{s.cutbacks} cutbacks, {s.wall:.2f} s; results in {result.directory}")
    return EXIT_OK


def check(args: argparse.Namespace, interruption: Interruption) -> int:
    """The scene and everything it asks of its mesh (:class:`~dolfinx_friction.scene.build.
    DiscreteScene`); no forms, nothing solved."""
    scene = _scene(args)
    MPI = mpi.start()

    from dolfinx_friction.scene.build import DiscreteScene
    model = DiscreteScene(scene, MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank == 0:
        n_dofs = model.layout.n_global * model.gdim
        print(f"{args.scene}: ok ({model.gdim}D, {len(scene.bodies)} bodies, "
              f"{len(scene.contacts)} contact pairs, {len(scene.steps)} steps, {n_dofs} dofs)")
    return EXIT_OK


def _one_process(args: argparse.Namespace) -> None:
    if mpi.ranks() > 1:
        raise UsageError(f"{args.command} runs in one process (a sweep starts its own "
                         "runs): start it without mpirun")


def sweep(args: argparse.Namespace, interruption: Interruption) -> int:
    _one_process(args)
    from dolfinx_friction.cli.sweep import (WorkerPool, default_jobs, default_sweep_dir,
                                            expand, validate)
    _scene_file(args.scene)
    points = expand(args.sweeps)
    directory = args.out if args.out is not None else default_sweep_dir(args.scene)
    if directory.exists() and not directory.is_dir():
        raise UsageError(f"sweep folder {directory}: not a folder")
    with WorkerPool(min(args.jobs or default_jobs(), len(points))) as pool:
        validate(args.scene, points)  # (while the workers import)
        return _sweep(args, points, directory, pool)


def _sweep(args: argparse.Namespace, points: list[Point], directory: Path,
           pool: WorkerPool) -> int:
    """The validated points of ``sweep`` run on the pool, one line per point ended."""
    from dolfinx_friction.cli.sweep import SWEEP_CSV, run_sweep
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

    try:
        results = run_sweep(args.scene, points, directory, pool, report)
    except Interrupted as exc:  # (the running points are stopped and listed)
        error(f"sweep interrupted: {len(ended)} of {len(points)} points ended"
               + (f", listed in {table}" if ended else ""))
        return signal_status(exc.code)
    failed = [r for r in results if r.status != 0]
    if not args.quiet:
        print(f"sweep: {len(points)} points, {len(points) - len(failed)} converged, "
              f"{len(failed)} failed; table {table}")
    if failed:
        error(f"{len(failed)} of {len(points)} points failed (see the reason column of "
               f"{table})")
        return EXIT_DIVERGED
    return EXIT_OK


def _incomplete(run, what: str) -> int:
    """Exit status of a picture made: 2 (and the line) for a run killed half-way."""
    if run.complete:
        return EXIT_OK
    error(f"{run.directory}: the run is incomplete (history.csv but no summary.json): "
           f"{what}")
    return EXIT_INPUT


def plot(args: argparse.Namespace, interruption: Interruption) -> int:
    _one_process(args)
    from dolfinx_friction.io.reader import read_run
    from dolfinx_friction.viz.plots import plot_history, plot_sweep
    directory = args.directory
    if (directory / "sweep.csv").is_file():
        path, _ = plot_sweep(directory, args.output or directory / "sweep.png")
        print(f"chart: {path}")
        return EXIT_OK
    run = read_run(directory)
    path = plot_history(run, args.output or directory / "history.png")
    print(f"chart: {path}")
    return _incomplete(run, f"drew its {len(run.history)} converged increments into {path}")


def render(args: argparse.Namespace, interruption: Interruption) -> int:
    _one_process(args)
    if args.output is not None and args.output.suffix.lower() != ".png":
        raise UsageError(f"-o {args.output}: render writes PNG files (FILE.png)")
    from dolfinx_friction.viz.snapshot import render_files
    path, run, row = render_files(args.directory, args.output, args.increment,
                                  scalar="status" if args.scalar == "status"
                                  else "contact_pressure", warp=args.warp,
                                  amplify=args.amplify,
                                  body_scalar="von_mises" if args.von_mises else None)
    print(f"picture: {path}")
    return _incomplete(run, f"drew converged increment {row + 1} of {len(run.history)} "
                            f"into {path}")


#: The commands by name.
COMMANDS: dict[str, Callable[[argparse.Namespace, Interruption], int]] = {
    "run": run, "check": check, "sweep": sweep, "plot": plot, "render": render}
