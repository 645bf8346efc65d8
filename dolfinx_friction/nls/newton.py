"""Newton's method for one increment of a :class:`~dolfinx_friction.BlockProblem`, or
PETSc SNES instead.

Each iteration pairs the contacts at the accepted iterate (in their first
``pairing_iterations`` iterations), evaluates the residual and, unless converged,
solves with the Jacobian.  Converged (``convergence="residual"``, the default): the
residual norm is below ``max(rtol r_0, atol)`` or below its round-off floor.
``convergence="reactions"`` also stops when the reactions and the displacements no
longer change (:func:`settled`).  The line search halves the step (at most 5 times,
the pairing frozen) while the residual norm does not decrease.  Where a body's Jacobian
changes with the displacement (finite strain), a step after a whole step that changed no
contact status and cut the residual to :data:`~dolfinx_friction.nls.defaults.CHORD` of
its value or less solves with the last factorisation instead (a chord step: no Jacobian is
assembled or factorised; the next step takes a new one where the chord step contracted
less); the convergence test is the same.  Where the bodies are linear and every pair
frictionless, a step whose linearised problem changes a contact status solves for the
statuses (``solve_statuses``; :mod:`~dolfinx_friction.nls.normal_qp`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx_friction.nls.linear import (KRYLOV_RTOL, LinearSolver, forget_options,
                                     release_garbage, write_options)
from dolfinx_friction.nls.defaults import CHORD, CONVERGENCE, STALL_ITERATIONS, factorisation
from dolfinx_friction.fem.block_problem import BlockProblem


@dataclass
class NewtonTrace:
    """One Newton solve: ``residuals[k]`` is the residual norm at iterate k; in iteration
    k + 1, ``status_changes[k]`` slave nodes changed their contact status (open, stick,
    slip), ``face_changes[k]`` others only their master face, and the line search halved
    the step ``backtracks[k]`` times, its correction was ``corrections[k]`` (max norm)
    and the reactions changed by ``reaction_changes[k]`` (recorded with
    ``convergence="reactions"`` only); ``reason``: why it stopped unconverged, where known
    (a singular Jacobian)."""

    converged: bool = False
    residuals: list[float] = field(default_factory=list)
    corrections: list[float] = field(default_factory=list)
    reaction_changes: list[float] = field(default_factory=list)
    status_changes: list[int] = field(default_factory=list)
    face_changes: list[int] = field(default_factory=list)
    backtracks: list[int] = field(default_factory=list)
    reason: str = ""
    #: solves after the first, each after an augmented Lagrangian update (their
    #: iterations are joined to the first's)
    augmentations: int = 0

    @property
    def iterations(self) -> int:
        return len(self.backtracks)

    def extend(self, again: "NewtonTrace") -> None:
        """Join the trace of the solve that followed an augmented Lagrangian update."""
        for name in ("residuals", "corrections", "reaction_changes", "status_changes",
                     "face_changes", "backtracks"):
            getattr(self, name).extend(getattr(again, name))
        self.converged, self.reason = again.converged, again.reason
        self.augmentations += 1


class Newton:
    """Newton iterations from :attr:`BlockProblem.x` (contacts begun) to convergence.

    ``prefix`` and ``petsc_options`` set the linear solver (default MUMPS, with the
    factorisation kept as GMRES preconditioner where only contact changes the Jacobian;
    PETSc's own factorisation of every Jacobian for a small serial system,
    :func:`~dolfinx_friction.nls.defaults.factorisation`: see
    :mod:`dolfinx_friction.nls.linear`).  ``convergence``: ``"residual"`` (the residual
    norm test alone) or ``"reactions"`` (that test, or the reactions and displacements
    settled to ``reaction_tol``: :func:`settled`).  ``stall``: with ``solve(may_stall=True)``,
    give up after that many iterations without a new lowest residual (0: never; default
    :data:`~dolfinx_friction.nls.defaults.STALL_ITERATIONS`).  ``chord``: the contraction
    below which a finite-strain problem's next step reuses the last factorisation (0:
    never, a new Jacobian in every step; :meth:`_chord_step`).  ``solve_statuses``: where
    the bodies are linear, every pair frictionless with a bilinear law and the bulk
    factorisation kept (the condensed path), a step whose linearised problem changes a
    contact status solves for the statuses exactly (:mod:`~dolfinx_friction.nls.normal_qp`)
    instead of taking Newton's step on the iterate's statuses (False: never).
    """

    def __init__(self, rtol: float = 1e-9, atol: float = 1e-10, max_iterations: int = 30,
                 line_search: bool = True, prefix: str = "dolfinx_friction_",
                 petsc_options: Optional[dict] = None,
                 reuse_factorisation: Optional[bool] = None,
                 convergence: str = "residual", reaction_tol: float = 1e-5,
                 stall: int = STALL_ITERATIONS, chord: float = CHORD,
                 solve_statuses: bool = True):
        if convergence not in CONVERGENCE:
            raise ValueError(f"convergence = {convergence!r}: must be one of "
                             f"{', '.join(map(repr, CONVERGENCE))}")
        self.convergence, self.reaction_tol = convergence, reaction_tol
        self.rtol, self.atol, self.max_iterations = rtol, atol, max_iterations
        self.line_search = line_search
        self.stall, self.chord = stall, chord
        self.solve_statuses = solve_statuses
        self.prefix, self.petsc_options = prefix, petsc_options
        self.reuse_factorisation = reuse_factorisation
        self.linear: Optional[LinearSolver] = None

    def _solver(self, problem: BlockProblem) -> LinearSolver:
        if self.linear is None:
            reuse = self.reuse_factorisation
            package = factorisation(problem.x.getSize(), problem.gdim, problem.comm.size)
            if reuse is None and self.petsc_options is None:
                # a kept factorisation pays where only contact changes, and MUMPS's costs
                reuse = problem.linear and package == "mumps"
            self.linear = LinearSolver(problem.comm, self.prefix, reuse, self.petsc_options,
                                       symmetric=problem.symmetric, package=package)
        return self.linear

    def release(self, problem: BlockProblem) -> None:
        """Free what the solves of ``problem`` left (collective, at the end of a run): the
        linear solver's factorisations (:meth:`LinearSolver.release`) and the PETSc objects
        Python has collected on the communicators of ``problem``'s meshes, which petsc4py
        destroys only in ``PETSc.garbage_cleanup`` (Jacobians, solvers and vectors replaced
        during the run, and those of earlier runs on the same meshes).  No collection is
        forced (17 ms and more: a tenth of a small run); what waits in a reference cycle is
        freed at a later call."""
        if self.linear is not None:
            self.linear.release()
        release_garbage(V.mesh.comm for V in problem.spaces)

    @staticmethod
    def _evaluate(problem: BlockProblem, pairing: bool, last: Optional[float] = None) -> float:
        """Update the contacts at :attr:`BlockProblem.x` and return the residual norm;
        ``last``: the norm of the residual already in :attr:`BlockProblem.b` for this
        ``x``, kept when no contact was evaluated anew (the pairing did not change)."""
        evaluations = [c.evaluations for c in problem.contacts]
        with problem.timers.measure("contact_search"):
            for c in problem.contacts:
                c.update(problem.x, pairing=pairing)
        if last is not None and evaluations == [c.evaluations for c in problem.contacts]:
            return last
        return problem.residual(problem.x, problem.b)

    def solve(self, problem: BlockProblem, start: Optional[PETSc.Vec] = None,
              may_stall: bool = False) -> NewtonTrace:
        """Iterate from :attr:`BlockProblem.x` to convergence; ``start``: the converged
        state the increment starts from (default: ``x`` on entry), the scale of the
        displacement test of ``convergence="reactions"``; ``may_stall``: give up after
        :attr:`stall` iterations without a new lowest residual (where the caller can cut
        back: :func:`~dolfinx_friction.nls.stepping.solve_steps` while cutbacks are left;
        else only ``max_iterations`` stops it).  A converged state in which a body can move
        rigidly with nothing to hold it raises :class:`~dolfinx_friction.ContactSetupError`
        (:meth:`BlockProblem.check_held`)."""
        x, b = problem.x, problem.b
        dx = x.duplicate()
        settling = self.convergence == "reactions"
        x_n = (x.copy() if start is None else start) if settling else None
        trace = NewtonTrace()
        before, reactions, floor, evaluated = None, None, 0.0, None
        best, best_at = np.inf, 1  # the lowest residual after the first step
        for it in range(self.max_iterations + 1):
            norm = self._evaluate(problem, True, evaluated)  # pairing at the accepted iterate
            trace.residuals.append(norm)
            now = [c.pairing() for c in problem.contacts]
            if before is not None:
                _record_changes(problem, before, now, trace)
            before = now
            if not np.isfinite(norm):
                break
            if settling:
                reactions = self._reactions(problem, reactions, trace)
            if it and norm < best:
                best, best_at = norm, it
            target = self.target(problem, trace.residuals[0])
            floor = _floor_if_near(problem, norm, target, floor, it == 0)
            if norm <= max(target, floor) or (
                    settling and settled(trace, problem, x, x_n, reactions, self.reaction_tol)):
                trace.converged = True
                break
            if it == self.max_iterations:
                break
            if may_stall and 0 < self.stall <= it - best_at:
                trace.reason = f"no new lowest residual in {self.stall} iterations"
                break
            krylov_rtol = forcing(norm, trace.residuals[0], target)
            if not self._step(problem, trace, x, b, dx, krylov_rtol):
                trace.backtracks.append(0)
                trace.reason = self.linear.failure
                break
            x.axpy(-1.0, dx)
            trace.corrections.append(dx.norm(PETSc.NormType.NORM_INFINITY))
            halvings, evaluated = (self._line_search(problem, dx, norm, target, floor)
                                   if self.line_search else (0, None))
            trace.backtracks.append(halvings)
        dx.destroy()
        if settling and start is None:
            x_n.destroy()
        problem.scatter()
        if trace.converged:
            problem.check_held()
        return trace

    def _step(self, problem: BlockProblem, trace: NewtonTrace, x: PETSc.Vec, b: PETSc.Vec,
              dx: PETSc.Vec, krylov_rtol: float) -> bool:
        """Solve ``J dx = b`` at ``x`` the cheapest way that applies; whether it solved.  A
        chord step with the last factorisation (:meth:`_chord_step`); else the Jacobian as
        bulk plus contact with the bulk's factorisation kept, where the solver keeps one
        and that pays (:meth:`LinearSolver.solve_split`); else the whole Jacobian,
        assembled (a Krylov solver stops at ``krylov_rtol``)."""
        solver = self._solver(problem)
        if self._chord_step(problem, trace):
            with problem.timers.measure("linear_solve"):
                if solver.solve_again(b, dx):
                    return True
        split = problem.split() if solver.reuse else None
        if split is not None:
            # (where Newton's own last step changed no status, its next one seldom does)
            models = (problem.normal_models() if self.solve_statuses and (
                not trace.status_changes or trace.status_changes[-1]) else None)
            with problem.timers.measure("linear_solve"):
                solved = solver.solve_contact(split, models, b, dx) if models else None
                if solved is None:
                    solved = solver.solve_split(split, b, dx)
            if solved is not None:
                return solved
        A = problem.jacobian(x, symmetric=solver.symmetric)
        with problem.timers.measure("linear_solve"):
            return solver.solve(A, b, dx, krylov_rtol, problem.constrained_rows,
                                problem.linear_interior())

    def _chord_step(self, problem: BlockProblem, trace: NewtonTrace) -> bool:
        """Whether the next step solves with the last factorisation instead of a new
        Jacobian: where a body's Jacobian changes with ``x`` (:attr:`BlockProblem.linear`
        false), the last step was whole, changed no slave node's status or master face,
        and cut the residual by at least :attr:`chord` (``r_k <= chord r_k-1``: the
        Jacobian barely moved along it)."""
        r = trace.residuals
        return (self.chord > 0.0 and not problem.linear and len(r) >= 2
                and trace.backtracks[-1] == 0 and trace.status_changes[-1] == 0
                and trace.face_changes[-1] == 0 and r[-1] <= self.chord * r[-2])

    def target(self, problem: BlockProblem, first: float) -> float:
        """The residual norm that converges at the last evaluated iterate (collective):
        ``rtol`` times the smaller of the increment's ``first`` residual and the forces now
        (:meth:`BlockProblem.force_scale`), at least ``atol``.  A first residual that a
        prescribed jump on a stiff body inflates far above the forces the increment carries
        would otherwise accept an iterate whose unbalanced force is a fair share of them."""
        return max(self.rtol * min(first, problem.force_scale()), self.atol)

    def residual_tolerance(self, problem: BlockProblem) -> float:
        """The largest residual norm the convergence test accepts at the last evaluated
        (converged) iterate: the :meth:`target` against the forces, or the round-off
        floor; with ``convergence="reactions"`` also ``sqrt(rows) reaction_tol`` times the
        forces (:func:`settled` bounds every row by ``reaction_tol`` times them).  What
        :meth:`BlockProblem.postcondition` checks the increment against."""
        force = problem.force_scale()
        tolerance = max(self.rtol * force, self.atol, problem.roundoff_floor())
        if self.convergence == "reactions":
            tolerance = max(tolerance, np.sqrt(problem.x.getSize()) * self.reaction_tol * force)
        return tolerance

    @staticmethod
    def _reactions(problem: BlockProblem, last: Optional[np.ndarray],
                   trace: NewtonTrace) -> np.ndarray:
        """The internal forces of the constrained rows (the reactions) at this iterate;
        records their largest change since ``last`` (all ranks)."""
        now = problem.internal[problem.constrained_rows]
        if last is not None:
            change = float(np.abs(now - last).max(initial=0.0))
            trace.reaction_changes.append(problem.comm.allreduce(change, op=MPI.MAX))
        return now

    def _line_search(self, problem: BlockProblem, dx: PETSc.Vec, norm0: float,
                     target: float, floor: float) -> tuple[int, Optional[float]]:
        """Choose the step ``x <- x - alpha dx`` (``x`` enters at ``alpha = 1``, the residual
        ``b`` still that of ``x + dx``); returns the residuals evaluated beyond the whole
        step's and the residual norm at the accepted ``x`` (None: not evaluated).

        The whole step is taken where it lowers the residual norm or converges.  Else the
        slope ``s(alpha) = -dx . R(x + dx - alpha dx)`` decides: the derivative of the
        potential energy along the step, where the bodies and the contact have one
        (``s(0) < 0`` for a Newton step on a positive definite Jacobian).  Still negative at
        the whole step, the energy fell all the way: the step is taken (a node that the
        step closes raises the residual norm by its penalty force at any fraction of it,
        and halving the step only shrinks the progress).  Positive, the step went past the
        minimum along it: ``alpha`` where the slope is within half of ``|s(0)|`` of zero
        (regula falsi, Illinois; at most :data:`LINE_SEARCH_STEPS` residuals).  Without a
        descent slope (``s(0) >= 0``: a non-symmetric friction tangent) the step is halved
        while the residual norm does not decrease (at round-off it need not)."""
        s0 = -dx.dot(problem.b)
        norm = self._evaluate(problem, False)
        floor = _floor_if_near(problem, norm, target, floor, False)
        if norm <= max((1.0 - 1e-4) * norm0, target, floor):
            return 0, norm
        if s0 < 0.0:
            s1 = -dx.dot(problem.b)
            return (0, norm) if s1 <= 0.0 else self._slope_search(problem, dx, s0, s1, target,
                                                                  floor)
        alpha = 1.0
        for halvings in range(1, LINE_SEARCH_STEPS + 1):
            alpha *= 0.5
            problem.x.axpy(alpha, dx)  # back from x - 2 alpha dx to x - alpha dx
            norm = self._evaluate(problem, False)
            floor = _floor_if_near(problem, norm, target, floor, False)
            if norm <= max((1.0 - 1e-4 * alpha) * norm0, target, floor):
                return halvings, norm
        return LINE_SEARCH_STEPS, norm

    def _slope_search(self, problem: BlockProblem, dx: PETSc.Vec, s0: float, s1: float,
                      target: float, floor: float) -> tuple[int, float]:
        """Regula falsi (Illinois) for the zero of the slope between ``alpha = 0`` (``s0 <
        0``) and the whole step (``s1 > 0``, ``x`` there); stops where ``|s| <= |s0| / 2``
        or the residual converges."""
        lo, s_lo, hi, s_hi, alpha, side = 0.0, s0, 1.0, s1, 1.0, 0
        for evaluations in range(1, LINE_SEARCH_STEPS + 1):
            new = hi - s_hi * (hi - lo) / (s_hi - s_lo)
            new = min(max(new, lo + 0.02 * (hi - lo)), hi - 0.02 * (hi - lo))
            problem.x.axpy(alpha - new, dx)
            alpha = new
            norm = self._evaluate(problem, False)
            floor = _floor_if_near(problem, norm, target, floor, False)
            s = -dx.dot(problem.b)
            if abs(s) <= 0.5 * abs(s0) or norm <= max(target, floor):
                break
            if s > 0.0:
                hi, s_hi = alpha, s
                s_lo = s_lo * 0.5 if side == 1 else s_lo  # Illinois: the same side again
                side = 1
            else:
                lo, s_lo = alpha, s
                s_hi = s_hi * 0.5 if side == -1 else s_hi
                side = -1
        return evaluations, norm


#: residual evaluations a line search may add to the whole step's
LINE_SEARCH_STEPS = 5


#: the largest relative linear residual of a Newton step (:func:`forcing`): 1e-5 already
#: costs a Newton iteration on the 16k-dof frictional block, 1e-6 none
FORCING_MAX = 1e-6


def forcing(norm: float, first: float, target: float) -> float:
    """The relative linear residual a Newton step at residual ``norm`` may leave (inexact
    Newton; ``first``: the increment's first residual, ``target``: the one that converges):
    ``0.1 norm / first`` (the next residual is at most that share of ``norm`` plus Newton's
    quadratic term: the iteration stays quadratic relative to ``first``), or ``0.1 target /
    norm`` where that is larger (a step need not be more accurate than the target asks);
    at most :data:`FORCING_MAX`, at least :data:`~dolfinx_friction.nls.linear.KRYLOV_RTOL`.  A
    kept factorisation's GMRES then needs fewer iterations."""
    if not (first > 0.0 and norm > 0.0):
        return KRYLOV_RTOL
    return max(KRYLOV_RTOL, min(FORCING_MAX, max(0.1 * norm / first, 0.1 * target / norm)))


#: the round-off floor is computed again when the residual norm comes within this factor
#: of the last one computed (it changes little within an increment: |x| and the contact
#: forces change by the increment), and at the increment's first iterate
FLOOR_MARGIN = 100.0


def _floor_if_near(problem: BlockProblem, norm: float, target: float, floor: float,
                   first: bool) -> float:
    """The residual's round-off floor (:meth:`BlockProblem.roundoff_floor`) where it may
    decide convergence, else the last one computed: an |J| |x| product saved per
    evaluation.  ``norm`` is the same on every rank, so all of them compute it or none."""
    if first or (target < norm <= FLOOR_MARGIN * floor):
        return problem.roundoff_floor()
    return floor


def settled(trace: NewtonTrace, problem: BlockProblem, x: PETSc.Vec, x_n: PETSc.Vec,
            reactions: np.ndarray, tol: float) -> bool:
    """The test of ``convergence="reactions"`` at iterate k >= 2 (collective).

    With ``F`` the force scale (the largest reaction or external force) and ``u`` the
    increment's largest displacement ``|x - x_n|``: no slave node changed its contact
    status or master face and the line search took the whole step; the largest
    unbalanced force (residual) is below ``tol F``; the corrections contract (theta =
    ``|dx_k| / |dx_k-1|`` < 1, max norms) and the changes still to come, estimated as
    theta / (1 - theta) times the last ones (a contraction's a posteriori bound), are
    below ``tol u`` for the displacements and ``tol F`` for the reactions.
    """
    if len(trace.corrections) < 2 or trace.status_changes[-1] or trace.face_changes[-1] \
            or trace.backtracks[-1]:
        return False
    last, before = trace.corrections[-1], trace.corrections[-2]
    theta = last / before if before > 0.0 else 0.0
    if theta >= 1.0:
        return False
    force = max(float(np.abs(reactions).max(initial=0.0)),
                float(np.abs(problem.f_ext).max(initial=0.0)))
    force = problem.comm.allreduce(force, op=MPI.MAX)
    if not problem.b.norm(PETSc.NormType.NORM_INFINITY) <= tol * force:
        return False
    moved = x_n.copy()
    moved.axpy(-1.0, x)
    u = moved.norm(PETSc.NormType.NORM_INFINITY)
    moved.destroy()
    ahead = theta / (1.0 - theta)
    return ahead * last <= tol * u and ahead * trace.reaction_changes[-1] <= tol * force


def _record_changes(problem: BlockProblem, before: list, now: list, trace: NewtonTrace) -> None:
    """Count (all ranks) the slave nodes whose status, or else only master face, changed."""
    counts = np.zeros(2, dtype=np.int64)
    for old, new in zip(before, now):
        differs = old != new
        counts += differs[:, 0].sum(), (differs[:, 1] & ~differs[:, 0]).sum()
    status, face = problem.comm.allreduce(counts)
    trace.status_changes.append(int(status))
    trace.face_changes.append(int(face))


def snes_solve(problem: BlockProblem, prefix: str = "dolfinx_friction_snes_",
               options: Optional[dict] = None) -> PETSc.SNES:
    """Solve an increment with PETSc SNES (``newtonls`` unless the options say otherwise;
    every SNES/KSP option and monitor under ``prefix`` applies).  The contacts must have
    begun; they are paired at every residual evaluation, without a new search (the
    couplings stay those of :meth:`BlockProblem.matrix`).  Returns the SNES, solved:
    ``getConvergedReason()`` (> 0: converged), ``getIterationNumber()``,
    ``getConvergenceHistory()`` (the residual norms); ``destroy()`` it when done.  A
    converged state in which a body can move rigidly with nothing to hold it raises
    :class:`~dolfinx_friction.ContactSetupError` (:meth:`BlockProblem.check_held`)."""
    defaults = {"snes_type": "newtonls", "snes_linesearch_type": "bt", "ksp_type": "preonly",
                "pc_type": "lu", "pc_factor_mat_solver_type": "mumps", "snes_rtol": 1e-9,
                "snes_atol": 1e-10}
    written = write_options(prefix, {**defaults, **(options or {})})
    snes = PETSc.SNES().create(problem.comm)
    snes.setOptionsPrefix(prefix)

    def residual(_snes, x, b):
        for c in problem.contacts:
            c.update(x, search=False)
        problem.residual(x, b)

    def jacobian(_snes, x, A, P):
        problem.jacobian(x, A)

    A = problem.matrix()
    snes.setFunction(residual, problem.b.duplicate())
    snes.setJacobian(jacobian, A, A)
    snes.setFromOptions()
    snes.setConvergenceHistory()
    try:
        snes.solve(None, problem.x)
    finally:
        forget_options(written)
    problem.scatter()
    if snes.getConvergedReason() > 0:
        problem.check_held()
    return snes


class SNESNewton(Newton):
    """PETSc SNES in :class:`Newton`'s place, for :func:`~dolfinx_friction.nls.stepping.solve_steps`:
    each increment by :func:`snes_solve` under ``prefix`` with ``options`` (its
    ``snes_rtol``/``snes_atol`` are also the tolerances of the postcondition).  The trace
    holds the residual norms SNES recorded; the contact's status changes are not counted."""

    def __init__(self, prefix: str = "dolfinx_friction_snes_", options: Optional[dict] = None):
        options = dict(options or {})
        super().__init__(rtol=float(options.get("snes_rtol", 1e-9)),
                         atol=float(options.get("snes_atol", 1e-10)), prefix=prefix)
        self.options = options

    def solve(self, problem: BlockProblem, start: Optional[PETSc.Vec] = None,
              may_stall: bool = False) -> NewtonTrace:
        snes = snes_solve(problem, self.prefix, self.options)
        reason, its = snes.getConvergedReason(), snes.getIterationNumber()
        norms = [float(r) for r in snes.getConvergenceHistory()[0][: its + 1]]
        snes.destroy()
        zeros = [0] * its
        return NewtonTrace(converged=reason > 0, residuals=norms, status_changes=zeros,
                           face_changes=list(zeros), backtracks=list(zeros),
                           reason="" if reason > 0 else f"SNES stopped ({reason})")
