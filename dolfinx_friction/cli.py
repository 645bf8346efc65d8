"""``dolfinx-friction run|check``: the command line of scene-format.md."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Optional, Sequence

from dolfinx_friction.errors import EXIT_INPUT, classify
from dolfinx_friction.scene import SceneError, load_scene


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # one line, no usage dump
        print(f"dolfinx-friction: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_INPUT)


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="dolfinx-friction",
                     description="Node-to-surface penalty contact with Coulomb friction "
                                 "(CalculiX scheme) on Gmsh scenes, solved with DOLFINx/PETSc.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of errors")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    run = sub.add_parser("run", help="solve a scene and write its results")
    run.add_argument("scene", type=Path)
    run.add_argument("--out", type=Path, help="output directory (overrides [output] dir)")
    run.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene value by dotted path, e.g. contact.0.mu=0.2")
    run.add_argument("--quiet", action="store_true", help="no progress output")
    run.add_argument("--debug", action="store_true", help=argparse.SUPPRESS)
    check = sub.add_parser("check", help="validate a scene and its mesh, solve nothing")
    check.add_argument("scene", type=Path)
    check.add_argument("--set", dest="overrides", action="append", default=[],
                       metavar="KEY=VALUE")
    check.add_argument("--debug", action="store_true", help=argparse.SUPPRESS)
    return parser


def _check(args) -> None:
    from mpi4py import MPI
    from dolfinx_friction.problem import ContactProblem
    scene = load_scene(args.scene, args.overrides)
    problem = ContactProblem(scene, MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank == 0:
        n_dofs = problem.layout.n_global * problem.gdim
        print(f"{args.scene}: ok ({problem.gdim}D, {len(scene.bodies)} bodies, "
              f"{len(scene.contacts)} contact pairs, {len(scene.steps)} steps, {n_dofs} dofs)")


def _run(args) -> None:
    from dolfinx_friction.api import run
    result = run(args.scene, out=args.out, overrides=args.overrides, quiet=args.quiet)
    from mpi4py import MPI
    if MPI.COMM_WORLD.rank == 0 and not args.quiet:
        s = result.summary
        print(f"done: {s.increments} increments, {s.newton_iterations} Newton iterations, "
              f"{s.cutbacks} cutbacks, {s.wall:.2f} s; results in {result.directory}")


def main(argv: Optional[Sequence[str]] = None) -> int:
    args = _parser().parse_args(argv)
    try:
        if not args.scene.is_file():
            raise SceneError(f"{args.scene}: no such scene file")
        _run(args) if args.command == "run" else _check(args)
    except Exception as exc:  # one line on stderr, a traceback only with --debug
        status, message = classify(exc)
        if args.debug or status is None:
            raise
        print(f"dolfinx-friction: error: {message}", file=sys.stderr)
        return status
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
