"""Shared plumbing of the demo scripts: command line, mesh building, run, picture, timing.

Every demo is ``demos/<name>.py`` + ``demos/<name>.toml`` + the generated
``demos/<name>.msh``.  Its ``main()`` builds the mesh if it is missing (or with
``--rebuild``), runs the scene through :func:`dolfinx_friction.scene.runner.run`
(:func:`command_line` and :func:`run_demo`), renders PNGs next to the results
and prints the key numbers against the analytic reference.  The gmsh helpers
of ``build_mesh`` are in ``_meshing`` (no pyvista there).

Import order matters: pyvista (imported by ``dolfinx_friction.viz.pictures``) must be
loaded before dolfinx, so the demo scripts import this module first.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Callable

HERE = Path(__file__).resolve().parent
if str(HERE.parent) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(HERE.parent))

from dolfinx_friction.viz import pictures as viz  # noqa: E402  (pyvista before dolfinx)
from dolfinx_friction.reference.compare import contact_state  # noqa: E402,F401  (for the demos)
from mpi4py import MPI  # noqa: E402

import numpy as np  # noqa: E402

if TYPE_CHECKING:
    from dolfinx_friction.scene.runner import RunResult
    from dolfinx_friction.scene.driver import Increment


def parse_args(description: str, argv=None) -> argparse.Namespace:
    """The demos' command line (``--scene``, ``--out``, ``--set``, ``--rebuild``, ...)."""
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--scene", help="scene file (default: the demo's own)")
    p.add_argument("--out", help="output directory (default: <scene stem>_results next to it)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scene value, as in the CLI (repeatable)")
    p.add_argument("--rebuild", action="store_true", help="regenerate the mesh first")
    p.add_argument("--no-render", action="store_true", help="skip the pictures")
    p.add_argument("--quiet", action="store_true", help="no per-increment progress")
    return p.parse_args(argv)


def ensure_mesh(path: Path, build: Callable[..., None], rebuild: bool = False,
                **resolution) -> float:
    """Build the mesh on rank 0 if missing (or ``rebuild``); returns the seconds spent."""
    comm = MPI.COMM_WORLD
    t0 = time.perf_counter()
    if comm.rank == 0 and (rebuild or not path.exists()):
        build(path, **resolution)
        print(f"mesh written: {path} ({path.stat().st_size / 1024:.0f} kB, "
              f"{time.perf_counter() - t0:.1f} s)")
    comm.barrier()
    return time.perf_counter() - t0


def run_scene(scene: Path, args: argparse.Namespace):
    """Run a scene with the command-line overrides; returns (RunResult, seconds)."""
    from dolfinx_friction.scene.runner import run
    from dolfinx_friction.cli.progress import Progress
    progress = Progress() if MPI.COMM_WORLD.rank == 0 and not args.quiet else None
    t0 = time.perf_counter()
    try:
        result = run(scene, out=args.out, overrides=args.set, progress=progress)
    finally:
        if progress is not None:
            progress.close()
    return result, time.perf_counter() - t0


def command_line(doc: str, default_scene: Path, argv=None) -> tuple[argparse.Namespace, Path]:
    """Parse the command line (described by the first line of ``doc``); returns (args, scene)."""
    args = parse_args(doc.splitlines()[0], argv)
    return args, Path(args.scene) if args.scene else default_scene


def run_demo(args: argparse.Namespace, scene: Path, mesh: Path, build: Callable[..., None],
             **resolution) -> RunResult:
    """Build ``mesh`` if needed, run ``scene`` and report the iterations; returns the RunResult."""
    ensure_mesh(mesh, build, args.rebuild, **resolution)
    result, seconds = run_scene(scene, args)
    report(result, seconds)
    return result


def render(result: RunResult, name: str, **kwargs) -> None:
    """PNG ``<name>.png`` in the result directory (rank 0 renders; collective)."""
    path = Path(result.directory) / f"{name}.png"
    out = viz.render(result, path, **kwargs)
    if out is not None:
        print(f"picture: {out}")


def render_status_and_pressure(result: RunResult, name: str, **kwargs) -> None:
    """PNGs ``<name>_status.png`` and ``<name>_pressure.png``: the same view, two colourings."""
    render(result, f"{name}_status", scalar="status", **kwargs)
    render(result, f"{name}_pressure", **kwargs)


def report(result: RunResult, seconds: float) -> None:
    """Newton iterations per increment and the wall time."""
    if MPI.COMM_WORLD.rank != 0:
        return
    its = [inc.iterations for inc in result.increments]
    s = result.summary
    print(f"run: {s.increments} increments, {s.cutbacks} cutbacks, Newton iterations per "
          f"increment {its}, {seconds:.1f} s wall (solver {s.wall:.1f} s)")


def increment_line(inc: Increment) -> str:
    """``step increment slipping/active`` of one increment, the start of a table row."""
    return f"{inc.step_name:>6} {inc.increment:3d}   {inc.slipping:3d}/{inc.active:3d}"


def pyplot():
    """matplotlib.pyplot without a display."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def save_figure(fig, result: RunResult, name: str) -> None:
    """Save a matplotlib figure as ``<name>.png`` in the result directory and close it."""
    path = Path(result.directory) / f"{name}.png"
    fig.tight_layout()
    fig.savefig(path)
    pyplot().close(fig)
    print(f"picture: {path}")


def profile_plot(result: RunResult, name: str, x: np.ndarray, p: np.ndarray,
                 reference: tuple[np.ndarray, np.ndarray, str], a_fit: float, xlabel: str,
                 title: str, ms: float = 4) -> None:
    """Nodal pressures ``p(x)`` against ``reference = (xs, ps, label)`` and the fitted ``a``."""
    xs, ps, label = reference
    fig, ax = pyplot().subplots(figsize=(6.4, 4.0), dpi=120)
    ax.plot(xs, ps, "k-", label=label)
    ax.plot(x, p, "o", ms=ms, color="#d62728", label="nodal F_N / A_p")
    ax.axvline(a_fit, color="#1f77b4", ls=":", label=f"fitted a = {a_fit:.4f}")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("contact pressure")
    ax.set_xlim(0, xs[-1])
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    save_figure(fig, result, name)


def root_print(*args, **kwargs) -> None:
    """print() on rank 0 only."""
    if MPI.COMM_WORLD.rank == 0:
        print(*args, **kwargs)


def relerr(got: float, want: float) -> str:
    """Relative error of ``got`` against ``want`` in per cent, signed."""
    return f"{100.0 * (got - want) / want:+.2f} %"
