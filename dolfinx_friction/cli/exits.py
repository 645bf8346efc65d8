"""The exit statuses of the command line, and which exception means which.

0 done; 1 an internal error (a bug: the line asks for ``--debug``); 2 bad input (the
scene, the mesh, an option, a results folder, the output directory or another file: one
line naming it); 3 a step that failed after all its cutbacks (or a sweep with a failed
point); 128 + the signal for a command stopped by SIGINT (130) or SIGTERM (143).
"""
from __future__ import annotations

import signal
import sys
from typing import Optional

from dolfinx_friction.cli import mpi

__all__ = ["EXIT_OK", "EXIT_INTERNAL", "EXIT_INPUT", "EXIT_DIVERGED", "EXIT_SIGNAL",
           "signal_status", "classify", "error"]

EXIT_OK, EXIT_INTERNAL, EXIT_INPUT, EXIT_DIVERGED = 0, 1, 2, 3
#: Exit status of a command ended by a signal: 128 + its number, as a shell reports it.
EXIT_SIGNAL = {signal.SIGINT: 130, signal.SIGTERM: 143}

# (module, class) of the errors that blame the input, and of a failed solve.  Looked up
# in sys.modules rather than imported: an exception of a module that was never imported
# cannot be raised, and a bad scene is then answered without importing dolfinx.
_INPUT_ERRORS = (("dolfinx_friction.scene.validation", "SceneError"),
                 ("dolfinx_friction.scene.validation", "ModelError"),
                 ("dolfinx_friction.io.msh", "MeshError"),
                 ("dolfinx_friction.errors", "ContactSetupError"),  # a body left free
                 ("dolfinx_friction.io.reader", "ResultsError"),
                 ("dolfinx_friction.cli.sweep", "SweepError"),
                 ("dolfinx_friction.cli.commands", "UsageError"))
_DIVERGED_ERRORS = (("dolfinx_friction.errors", "ConvergenceError"),)


def signal_status(signum: int) -> int:
    """The exit status of a command stopped by signal ``signum``."""
    return EXIT_SIGNAL.get(signum, 128 + signum)


def _is(exc: BaseException, classes) -> bool:
    for module, name in classes:
        cls = getattr(sys.modules.get(module), name, None)
        if cls is not None and isinstance(exc, cls):
            return True
    return False


def classify(exc: BaseException) -> tuple[Optional[int], str]:
    """Exit status and one-line message of an expected error; ``(None, message)`` for a
    bug.  An OSError (the output directory, a file that cannot be written) is the input's
    fault: ``<file>: <reason>``."""
    message = " ".join(str(exc).split())
    if _is(exc, _INPUT_ERRORS):
        return EXIT_INPUT, message
    if _is(exc, _DIVERGED_ERRORS):
        return EXIT_DIVERGED, f"diverged: {message}"
    if isinstance(exc, OSError):
        if exc.filename and exc.strerror:
            message = " ".join(f"{exc.filename}: {exc.strerror}".split())
        return EXIT_INPUT, message
    return None, message


def error(message: str) -> None:
    """The one line ``dolfinx-friction: error: <message>`` on stderr (rank 0 only)."""
    if mpi.rank() == 0:
        print(f"dolfinx-friction: error: {message}", file=sys.stderr, flush=True)
