"""Which exceptions are the user's input at fault, and which a failed solve."""
from __future__ import annotations

import os
import sys
import threading
from typing import Optional

EXIT_INTERNAL, EXIT_INPUT, EXIT_DIVERGED = 1, 2, 3


class OutputError(OSError):
    """The output directory cannot be prepared or written."""


# (module, class) of the errors that blame the input.  Looked up in sys.modules
# rather than imported: an exception of a module that was never imported cannot
# be raised, and a bad scene is then answered without importing dolfinx.
_INPUT_ERRORS = (("dolfinx_friction.scene.validation", "SceneError"),
                 ("dolfinx_friction.io.msh", "MeshError"),
                 ("dolfinx_friction.scene.validation", "ModelError"),
                 ("dolfinx_friction.errors", "OutputError"))
_DIVERGED_ERRORS = (("dolfinx_friction.scene.driver", "ConvergenceError"),)


def _is(exc: BaseException, classes) -> bool:
    for module, name in classes:
        cls = getattr(sys.modules.get(module), name, None)
        if cls is not None and isinstance(exc, cls):
            return True
    return False


def classify(exc: BaseException) -> tuple[Optional[int], str]:
    """Exit status and one-line message for an expected error; (None, ...) for a bug."""
    message = " ".join(str(exc).split())
    if _is(exc, _INPUT_ERRORS):
        return EXIT_INPUT, message
    if _is(exc, _DIVERGED_ERRORS):
        return EXIT_DIVERGED, f"diverged: {message}"
    return None, message


# ------------------------------------------------------------------ signals
#: Exit status of a run ended by a signal: 128 + the signal's number, as a shell reports it.
EXIT_SIGNAL = {2: 130, 15: 143}  # SIGINT, SIGTERM


class Interrupted(BaseException):
    """A run stopped by SIGINT or SIGTERM.  A BaseException (like KeyboardInterrupt), so
    that no ``except Exception`` on the way out takes it for a failure of the solve."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


class Interruption:
    """What the command line's signal handler needs to know and to do (one per process).

    The handler (``cli._on_signal``) records the first signal.  While an increment is
    solved (``solving``) nothing is raised in the handler: every rank raises
    :class:`Interrupted` at the next :meth:`checkpoint`, a collective call (the solver's
    residual evaluations and the end of each written increment), so that all ranks stop
    at the same place and none waits in a collective for a rank that left.  While an
    increment's results are written (``writing``) the signal only waits: an increment is
    written whole, then the checkpoint right after it stops the run (``where`` already
    names the next increment).  Elsewhere (set-up) the handler raises at once.

    ``where`` is the (step, increment) being solved, ``directory`` the results directory
    once it exists.  The one line is printed by rank 0 at the first moment it can be
    (in the handler, or at the checkpoint that learns of a signal another rank got):
    under ``mpirun`` the ranks get SIGTERM from the launcher and are killed one second
    later, so the line must not wait for the end of a long linear solve.
    """

    def __init__(self) -> None:
        self.armed = False  # handlers installed (the command line); else checkpoints are no-ops
        self.signum: Optional[int] = None
        self.received: Optional[int] = None  # the first signal the signal thread took
        self.announced = False
        self.solving = False
        self.writing = False
        self.where: Optional[tuple[int, int]] = None
        self.directory = None
        self.rank = 0
        self._lock = threading.RLock()  # RLock: the main thread's handler may run inside

    def line(self) -> str:
        if self.directory is None:
            return "dolfinx-friction: interrupted while setting up; no results were written"
        step, increment = self.where or (0, 1)
        return (f"dolfinx-friction: interrupted at step {step}, increment {increment}; "
                f"the results of converged increments are in {self.directory}")

    def announce(self) -> None:
        """Print the line (rank 0, once); ``os.write``: safe inside a signal handler, even
        while the interrupted code was printing to stderr itself."""
        with self._lock:  # the signal thread or the main thread, whichever comes first
            if self.announced:
                return
            self.announced = True
            if self.rank == 0:
                os.write(2, (self.line() + "\n").encode())

    def checkpoint(self, comm) -> None:
        """Collective: raise :class:`Interrupted` on every rank if any rank got a signal."""
        if not self.armed:
            return
        signum = self.signum or self.received or 0  # the handler may not have run yet
        if comm.size > 1:
            signum = comm.allreduce(signum, op=_max_op())
        if signum:
            self.signum = self.signum or signum
            self.announce()
            raise Interrupted(self.signum)


def _max_op():
    from mpi4py import MPI
    return MPI.MAX


#: The state of this process (used by the command line; inert in library use).
interruption = Interruption()
