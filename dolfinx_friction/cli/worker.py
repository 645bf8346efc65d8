"""A warm process for the points of a sweep: it imports the package, dolfinx and the form
compiler once and runs one ``run`` command line after another, in-process.

    python -m dolfinx_friction.cli.worker

Protocol (JSON lines): each line on stdin is the argv of one command (``["run", scene,
"--out", dir, "--quiet", "--set", ...]``); for each, one line on stdout,
``{"status": exit status, "stderr": what the command printed on stderr}``, exactly what
a fresh ``dolfinx-friction`` process would have given (its own stdout is discarded).  The
worker ends at the end of stdin, or after a command that was interrupted (exit 130 or
143: the sweep is being stopped), without the interpreter's teardown (:func:`leave`).  It
imports what a run needs (:func:`warm`) before it reads its first line, while the sweep
validates its points.  Nothing of a command stays
for the next one but the caches (imported modules, compiled kernels) and the run's
:class:`~dolfinx_friction.scene.workspace.Workspace` (meshes, spaces, compiled forms and
expressions, reused where the next point's scene agrees: results bit for bit those of a
fresh process): each ``main()`` builds its contact pairs, solvers and PETSc options afresh
and removes them.
"""
from __future__ import annotations

import json
import os
import sys
import tempfile
from typing import Optional

from dolfinx_friction.cli.exits import EXIT_INTERNAL
from dolfinx_friction.scene.workspace import Workspace

#: exit statuses after which the worker stops (the point was interrupted)
STOPPING = (130, 143)


def run_captured(argv: list[str], workspace: Optional[Workspace] = None) -> tuple[int, str]:
    """Run one command line in this process (with ``workspace``): its exit status and its
    stderr."""
    from dolfinx_friction.cli import frontend
    with tempfile.TemporaryFile(mode="w+") as err, open(os.devnull, "w") as null:
        sys.stdout.flush()
        sys.stderr.flush()
        saved = os.dup(1), os.dup(2)
        os.dup2(null.fileno(), 1)
        os.dup2(err.fileno(), 2)
        try:
            status = frontend.main(argv, workspace)
        except SystemExit as exc:  # (argparse's errors)
            status = exc.code if isinstance(exc.code, int) else EXIT_INTERNAL
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
        err.seek(0)
        return status, err.read()


def warm() -> None:
    """Import what every run imports (mpi4py, dolfinx, the form compiler, PETSc, the
    contact kernels), as a ``run`` would (MPI with :data:`~dolfinx_friction.cli.mpi.
    SINGLETON`); initialise numba (:func:`~dolfinx_friction.contact.backend.warm`)."""
    from dolfinx_friction.cli import frontend, mpi  # noqa: F401  (the commands)
    mpi.start()
    import dolfinx_friction.scene.runner  # noqa: F401
    from dolfinx_friction.contact import backend
    backend.warm()


def main() -> int:
    warm()
    protocol, workspace = sys.stdout, Workspace()
    for line in sys.stdin:
        status, stderr = run_captured(json.loads(line), workspace)
        protocol.write(json.dumps({"status": status, "stderr": stderr}) + "\n")
        protocol.flush()
        if status in STOPPING:
            return status
    return 0


def leave(status: int) -> None:
    """End the process now, as :mod:`multiprocessing`'s workers end: the output flushed, but
    not the interpreter's teardown of thousands of modules, PETSc and MPI (0.15 s, which the
    sweep waited for at its end).  Nothing is lost:
    every file of a point is complete and closed (its writer's memory folder removed)
    before the worker answers."""
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)


if __name__ == "__main__":
    leave(main())
