"""Shared plumbing of the demo scripts: command line, mesh building, run, picture, timing.

Every demo is ``demos/<name>.py`` + ``demos/<name>.toml`` + the generated
``demos/<name>.msh``.  Its ``main()`` builds the mesh if it is missing (or with
``--rebuild``), runs the scene through :func:`dolfinx_friction.api.run`,
renders PNGs next to the results and prints the key numbers against the
analytic reference.

Import order matters: pyvista (imported by ``dolfinx_friction.viz``) must be
loaded before dolfinx, so the demo scripts import this module first.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
if str(HERE.parent) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(HERE.parent))

from dolfinx_friction import viz  # noqa: E402  (pyvista before dolfinx)
from dolfinx_friction.postprocess import contact_state  # noqa: E402,F401  (for the demos)
from mpi4py import MPI  # noqa: E402

import numpy as np  # noqa: E402


def parse_args(description: str, argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--scene", help="scene file (default: the demo's own)")
    p.add_argument("--out", help="output directory (default: <scene stem>_results next to it)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scene value, as in the CLI (repeatable)")
    p.add_argument("--rebuild", action="store_true", help="regenerate the mesh first")
    p.add_argument("--no-render", action="store_true", help="skip the pictures")
    p.add_argument("--quiet", action="store_true", help="no per-increment progress")
    return p.parse_args(argv)


def ensure_mesh(path: Path, build, rebuild: bool = False, **resolution) -> float:
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
    from dolfinx_friction.api import run
    t0 = time.perf_counter()
    result = run(scene, out=args.out, overrides=args.set, quiet=args.quiet)
    return result, time.perf_counter() - t0


def render(result, name: str, **kwargs) -> None:
    """PNG ``<name>.png`` in the result directory (rank 0 renders; collective)."""
    path = Path(result.directory) / f"{name}.png"
    out = viz.render(result, path, **kwargs)
    if out is not None:
        print(f"picture: {out}")


def report(result, seconds: float) -> None:
    """Newton iterations per increment and the wall time."""
    if MPI.COMM_WORLD.rank != 0:
        return
    its = [inc.iterations for inc in result.increments]
    s = result.summary
    print(f"run: {s.increments} increments, {s.cutbacks} cutbacks, Newton iterations per "
          f"increment {its}, {seconds:.1f} s wall (solver {s.wall:.1f} s)")


def root_print(*args, **kwargs) -> None:
    if MPI.COMM_WORLD.rank == 0:
        print(*args, **kwargs)


def relerr(got: float, want: float) -> str:
    return f"{100.0 * (got - want) / want:+.2f} %"
