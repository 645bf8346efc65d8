"""Load stepping: increments with a predictor, cutbacks and rollback of the history.

A step ramps what ``load(t)`` prescribes from pseudo-time 0 to 1.  An increment whose
Newton iteration fails, whose converged state is not finite (displacements, reactions,
contact values), leaves a body unbalanced or a slave node beyond Coulomb (the
postcondition), or in which a whole contact zone vanishes off its master, is retried at
half the size after the displacement and the friction history are rolled back; the
history is committed only on convergence.
"""
from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass, field
from collections.abc import Sequence
from typing import Callable, Optional

import numpy as np

from dolfinx_friction.errors import ConvergenceError
from dolfinx_friction.nls.newton import Newton, NewtonTrace
from dolfinx_friction.fem.block_problem import BlockProblem
from dolfinx_friction.fem.contact_settings import MAX_AUGMENTATIONS


@dataclass
class IncrementRecord:
    """A converged increment of :func:`solve_steps`."""

    number: int  # 1, 2, ... within the step
    t: float  # pseudo-time reached, in (0, 1]
    trace: NewtonTrace
    cutbacks: int  # failed attempts before this one
    work: int  # Newton iterations spent on it, failed attempts included
    penetration: dict[str, float] = field(default_factory=dict)  # per contact: overclosure
    detached: dict[str, int] = field(default_factory=dict)  # per contact: slid off
    #: the largest force left unbalanced on a body or obstacle along an axis
    #: (:meth:`BlockProblem.imbalance`) and the size of the forces
    #: (:meth:`BlockProblem.force_scale`) [force]
    imbalance: float = 0.0
    force: float = 0.0
    #: the residual norm the convergence test accepts at the converged iterate
    #: (:meth:`Newton.residual_tolerance`): ``residuals[-1]`` is at most this [force]
    tolerance: float = 0.0

    @property
    def iterations(self) -> int:
        return self.trace.iterations

    @property
    def residuals(self) -> list[float]:
        return self.trace.residuals


_log = logging.getLogger(__name__)

#: why an increment whose Newton iteration converged is not a result (see :func:`_finite`)
NON_FINITE = "non-finite displacement, reaction or contact value"


def _finite(problem: BlockProblem) -> bool:
    """Whether what a converged increment reports is finite on every rank (collective):
    the unknowns (displacements, obstacle translations), the internal forces (reactions
    and obstacle forces are read from them) and every contact pair's state (the contact
    table and fields).  The residual norm leaves out constrained rows, so a converged
    norm does not tell that their reactions are finite."""
    ok = bool(np.isfinite(problem.x.getArray(readonly=True)).all()
              and np.isfinite(problem.internal).all())
    for c in problem.contacts:
        state = c.state() if ok and hasattr(c, "state") else None
        if state is not None and dataclasses.is_dataclass(state):
            ok = all(np.isfinite(np.asarray(getattr(state, f.name), dtype=float)).all()
                     for f in dataclasses.fields(state))
    return problem.comm.allreduce(int(not ok)) == 0


class IncrementSize:
    """Increment size of a step: halved when an increment fails; doubled back after
    ``needed`` easy increments (at most 4 Newton iterations) in a row.  A size that fails
    again right after growing back doubles ``needed``, so a size that keeps failing is
    retried ever more rarely instead of after every easy increment."""

    def __init__(self, increments: int):
        self.increments, self.level, self.easy, self.needed = increments, 0, 0, 1
        self._just_grew = False

    @property
    def current(self) -> float:
        return 1.0 / (self.increments * 2 ** self.level)

    def failed(self) -> None:
        if self._just_grew:
            self.needed *= 2
        self.level, self.easy, self._just_grew = self.level + 1, 0, False

    def converged(self, iterations: int) -> None:
        self.easy = self.easy + 1 if iterations <= 4 else 0
        self._just_grew = bool(self.level and self.easy >= self.needed)
        if self._just_grew:
            self.level, self.easy = self.level - 1, 0


def augment(problem: BlockProblem, newton: Newton, trace: NewtonTrace, start,
            may_stall: bool) -> None:
    """After a converged solve: while a contact pair with ``method="augmented"`` updates
    its multipliers (:meth:`~dolfinx_friction.NodeToSurface.augment`), solve the increment
    again from where it is, joining the iterations to ``trace``; ``trace`` ends
    unconverged where a solve fails or the updates exceed
    :data:`~dolfinx_friction.fem.contact_settings.MAX_AUGMENTATIONS`."""
    while trace.converged and any([c.augment() for c in problem.contacts
                                   if hasattr(c, "augment")]):
        if trace.augmentations == MAX_AUGMENTATIONS:
            trace.converged = False
            trace.reason = (f"the augmented Lagrangian updates did not bring the overclosure "
                            f"below its tolerance in {MAX_AUGMENTATIONS} solves")
            return
        trace.extend(newton.solve(problem, start=start, may_stall=may_stall))


def solve_steps(problem: BlockProblem, load: Callable[[float], None], increments: int = 1,
                newton: Optional[Newton] = None, max_cutbacks: int = 6,
                on_increment: Optional[Callable[[IncrementRecord], None]] = None,
                postcondition: bool = True, history: Sequence = ()) -> list[IncrementRecord]:
    """Ramp what ``load(t)`` prescribes from pseudo-time 0 to 1 in ``increments`` equal
    increments; returns the converged increments.

    ``load(t)`` sets everything prescribed at ``t``: the values of the Dirichlet
    conditions' Functions or Constants, obstacle translations, load Constants,
    :attr:`BlockProblem.f_ext`.  The displacement rate of the last increment predicts the
    next one (the first iterate: what the contacts measure at the start of an increment is
    taken from the converged state, so the predictor changes no answer).  ``on_increment``
    sees each converged increment before its history is committed.  ``postcondition``:
    an increment is accepted only where every body balances and every slave node obeys
    Coulomb (:meth:`BlockProblem.postcondition` against the residual the convergence test
    accepts, :meth:`Newton.residual_tolerance`); one that does not is cut back like one
    that diverged.  ``history``: the user's own state (objects with ``commit()`` and
    ``rollback()``, e.g. the quadrature-point state of a plasticity model), committed with
    the contacts' when an increment is accepted and rolled back with them before a cutback.
    Raises :class:`~dolfinx_friction.ConvergenceError`.
    """
    newton = newton or Newton()
    x = problem.x
    x_n, rate = x.duplicate(), None
    records: list[IncrementRecord] = []
    t, size, failures, spent = 0.0, IncrementSize(increments), 0, 0
    while t < 1.0 - 1e-12:
        dt = min(size.current, 1.0 - t)
        x.copy(x_n)
        load(t + dt)
        if rate is not None:
            x.axpy(dt, rate)
        problem.apply_bcs()
        for c in problem.contacts:
            c.begin(x, start=x_n)
        trace = newton.solve(problem, start=x_n, may_stall=size.level < max_cutbacks)
        augment(problem, newton, trace, x_n, size.level < max_cutbacks)
        spent += trace.iterations
        ok, why = trace.converged, trace.reason
        if ok and not _finite(problem):
            ok, why = False, NON_FINITE  # never a result: cut back
        tolerance = newton.residual_tolerance(problem) if ok else 0.0
        if ok and postcondition:
            why = problem.postcondition(tolerance)
            ok = not why
        if ok and size.level < max_cutbacks and any(c.zone_vanished()
                                                    for c in problem.contacts):
            ok = False  # too coarse to tell a slide off the master from a lost contact
        if not ok:
            _log.debug("increment %d at t = %.6g (dt = %.3g) cut back after %d Newton "
                       "iterations: %s", len(records) + 1, t + dt, dt, trace.iterations,
                       why or ("a contact zone vanished" if trace.converged
                               else f"not converged (residuals {trace.residuals[-3:]})"))
            for c in problem.contacts:
                c.rollback()
            for h in history:
                h.rollback()
            x_n.copy(x)
            problem.scatter()
            size.failed()
            failures += 1
            if size.level > max_cutbacks:
                why = problem.inadmissible or why
                raise ConvergenceError(
                    f"increment {len(records) + 1} at t = {t:.6g}: Newton did not converge "
                    f"after {max_cutbacks} cutbacks (last residual {trace.residuals[-1]:.3e}"
                    + (f": {why})" if why else ")"), len(records) + 1, t, trace.residuals[-1],
                    why, records, failures, spent)
            continue
        size.converged(trace.iterations)
        rate = rate if rate is not None else x.duplicate()
        rate.waxpy(-1.0, x_n, x)
        rate.scale(1.0 / dt)
        t += dt
        record = IncrementRecord(len(records) + 1, t, trace, failures, spent,
                                 {c.name: c.penetration() for c in problem.contacts},
                                 {c.name: c.detached() for c in problem.contacts},
                                 float(np.abs(problem.imbalance()).max(initial=0.0)),
                                 problem.force_scale(), tolerance)
        failures, spent = 0, 0
        records.append(record)
        if on_increment is not None:
            on_increment(record)
        for c in problem.contacts:
            c.commit()
        for h in history:
            h.commit()
    x_n.destroy()
    if rate is not None:
        rate.destroy()
    return records
