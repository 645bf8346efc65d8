"""How a caller follows and stops a run: the ``control`` of
:func:`~dolfinx_friction.scene.runner.run` and
:meth:`~dolfinx_friction.scene.driver.Solver.run`.

A run asks :meth:`RunControl.stop` at every *checkpoint*, a point that every rank reaches
together: each residual evaluation of the solve, and each converged increment before and
after it is written.  A nonzero answer on any rank raises
:class:`~dolfinx_friction.errors.Interrupted` there on every rank (with the largest
answer), so that all ranks stop at the same place and none waits in a collective for a
rank that left.  No checkpoint falls inside the writing of an increment: what is written
is written whole.  Without a control nothing is asked.
"""
from __future__ import annotations

from pathlib import Path
from typing import Optional

from dolfinx_friction.errors import Interrupted

__all__ = ["RunControl", "checkpoint"]


class RunControl:
    """The callbacks of a run; override what you need (the defaults never stop a run).

    The command line's (:mod:`dolfinx_friction.cli.signals`) answers the signal it got,
    and names in its one line the increment and the folder it learnt from here.
    """

    def begin(self, directory: Optional[Path]) -> None:
        """The set-up is done: from now until the run returns :meth:`stop` is asked at
        every checkpoint.  ``directory`` holds the results (None: nothing is written)."""

    def attempt(self, step: int, increment: int) -> None:
        """The increment the run works on from now (step from 0, increment from 1): an
        increment being solved, or the next one once the last is converged."""

    def stop(self) -> int:
        """Nonzero to stop the run at this checkpoint (the code of ``Interrupted``)."""
        return 0


def checkpoint(control: Optional[RunControl], comm) -> None:
    """Collective over ``comm``: raise :class:`~dolfinx_friction.errors.Interrupted` on
    every rank when ``control`` answers nonzero on any rank."""
    if control is None:
        return
    code = control.stop()
    if comm.size > 1:
        from mpi4py import MPI
        code = comm.allreduce(code, op=MPI.MAX)
    if code:
        raise Interrupted(code)
