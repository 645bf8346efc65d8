"""SIGINT and SIGTERM on the command line: one line, exit 130 / 143.

One handler for every command.  A command that is no run (``sweep``, ``plot``,
``render``), and a run while it sets up, stops where it is: the handler raises
:class:`~dolfinx_friction.errors.Interrupted`.  While a run solves and writes (from
:meth:`Interruption.begin` until the run returns) the handler only records the signal:
the :class:`Interruption` is the run's :class:`~dolfinx_friction.scene.control.RunControl`,
and the run stops at its next checkpoint, every rank together, increments written whole.

``run`` and ``check`` print their one line at once, from a thread that takes the signals:
Python runs a handler in the main thread only between bytecodes, not while it waits in
MPI, fsync or HDF5, and under ``mpirun`` that is too late (Open MPI sends the ranks
SIGTERM and kills them one second later, ``odls_base_sigkill_timeout``); that thread needs
only the GIL, which such waits release.  The other commands print their line where they
stop (``sweep``: how many points ended).
"""
from __future__ import annotations

import _thread
import os
import signal
import threading
from pathlib import Path
from typing import Optional

from dolfinx_friction.errors import Interrupted
from dolfinx_friction.scene.control import RunControl

__all__ = ["Interruption", "install"]

SIGNALS = {signal.SIGINT, signal.SIGTERM}
#: The commands that solve (under mpirun too): their line comes at once.
SOLVING = ("run", "check")


class Interruption(RunControl):
    """The signal state of one command, and the control of its run.

    ``signum`` is the first signal the handler took, ``received`` the first the signal
    thread took (it may come first); ``where`` the (step, increment) the run works on and
    ``directory`` its results folder, for the line; ``rank`` the launcher's rank (only
    rank 0 prints).
    """

    def __init__(self, command: str, rank: int = 0):
        self.command, self.rank = command, rank
        self.signum: Optional[int] = None
        self.received: Optional[int] = None
        self.announced = False
        self.running = False
        self.where: Optional[tuple[int, int]] = None
        self.directory: Optional[Path] = None
        self._lock = threading.RLock()  # RLock: the main thread's handler may run inside

    # ---------------------------------------------------------------- RunControl
    def begin(self, directory: Optional[Path]) -> None:
        self.directory, self.running = directory, True

    def attempt(self, step: int, increment: int) -> None:
        self.where = (step, increment)

    def stop(self) -> int:
        return self.signum or self.received or 0  # (the handler may not have run yet)

    def end(self) -> None:
        """The run returned: a signal from now on stops the command at once."""
        self.running = False

    # ---------------------------------------------------------------- the line
    def line(self) -> str:
        if self.command not in SOLVING:
            return f"dolfinx-friction: error: {self.command} interrupted"
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

    def stopped(self, code: int) -> int:
        """The signal that stopped the command (``code``: the Interrupted's), announced."""
        self.signum = self.signum or self.received or code
        self.announce()
        return self.signum


#: The command of this process (the handlers are installed once, for whichever comes).
_current: Optional[Interruption] = None
_watching = False


def _on_signal(signum: int, frame) -> None:
    state = _current
    if state is None or state.signum is not None:  # (a second Ctrl-C while stopping)
        return
    state.signum = signum
    if state.command in SOLVING:
        state.announce()
    if not state.running:
        raise Interrupted(signum)


def _watch() -> None:
    """Take SIGINT / SIGTERM (blocked in every other thread), print the line at once and
    hand the signal to the main thread's handler."""
    while True:
        signum = signal.sigwait(SIGNALS)
        state = _current
        if state is not None:
            state.received = state.received or signum
            if state.command in SOLVING:
                state.announce()  # (once: a second Ctrl-C says nothing more)
        _thread.interrupt_main(signum)  # runs _on_signal in the main thread


def install(command: str, rank: int) -> Interruption:
    """The signal state of ``command``, with the handler installed (in the main thread;
    called from another thread, signals stay the caller's)."""
    global _current, _watching
    _current = state = Interruption(command, rank)
    if threading.current_thread() is not threading.main_thread():
        return state
    for signum in SIGNALS:  # (even where SIG_IGN came in)
        signal.signal(signum, _on_signal)
    if command in SOLVING and not _watching:
        _watching = True
        signal.pthread_sigmask(signal.SIG_BLOCK, SIGNALS)  # inherited by later threads
        threading.Thread(target=_watch, daemon=True, name="dolfinx-friction-signals").start()
    return state
