"""A scene's load steps on the composable core: what each step prescribes, and reports.

Each step ramps prescribed displacements, loads and rigid-obstacle motions linearly from
their values at the start of the step to the step's totals (:class:`StepLoading`);
:func:`~dolfinx_friction.nls.stepping.solve_steps` takes the increments, with cutbacks, and
:class:`~dolfinx_friction.nls.newton.Newton` each increment.  Every converged increment is
reported as an :class:`Increment` (reactions, obstacle motions, contact counts).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

from dolfinx_friction.errors import ConvergenceError
from dolfinx_friction.nls import stepping
from dolfinx_friction.nls.newton import Newton
from dolfinx_friction.scene.build import ContactProblem
from dolfinx_friction.scene.control import RunControl, checkpoint
from dolfinx_friction.nls.stepping import IncrementRecord
from dolfinx_friction.fem.timers import Timers
from dolfinx_friction.fem.loads import unit_loads


@dataclass
class Increment:
    """A converged increment, as reported to observers."""

    step: int
    step_name: str
    increment: int
    t: float
    iterations: int
    residual: float
    residuals: list[float]
    status_changes: list[int]  # per iteration: slave nodes whose contact status changed
    face_changes: list[int]  # per iteration: other slave nodes whose master face changed
    backtracks: list[int]  # per iteration: residuals the line search added to the whole step's
    active: int
    slipping: int
    wall: float
    reactions: dict[str, np.ndarray]
    rigid_u: dict[str, np.ndarray]
    rigid_f: dict[str, np.ndarray]
    rigid_m: dict[str, np.ndarray]  # moment about the reference point: (1,) 2D (z), (3,) 3D
    penetration: dict[str, float]  # largest overclosure / slave spacing, per contact pair
    detached: dict[str, int]  # nodes in contact before that slid off the master surface
    imbalance: float  # largest unbalanced force on a body along an axis [force]
    force: float  # size of the forces (reactions, loads, contact) [force]
    tolerance: float  # the residual norm the convergence test accepts; residual <= it [force]


class _Enough(Exception):
    """Raised past the last increment a run was asked for (``max_increments``)."""


@dataclass
class RunSummary:
    increments: int = 0
    cutbacks: int = 0
    newton_iterations: int = 0
    converged: bool = False
    wall: float = 0.0
    timers: Timers = field(default_factory=Timers)
    failure: str = ""
    #: the linear solver's work: ``preconditioner_setups``, ``krylov_iterations``,
    #: ``condensed_solves``, ``contact_steps``, ``chord_solves`` (empty before a run; None if
    #: no solver ran)
    linear_solves: Optional[dict] = field(default_factory=dict)


class StepLoading:
    """What one step prescribes: constrained rows with values and external forces, both
    linear in the step's pseudo-time ``tau`` from their values at the step's start."""

    def __init__(self, rows: np.ndarray, u_start, u_end, f_start, f_end, first: bool,
                 pressures: list, rotations: list):
        self.rows, self.u_start, self.u_end, self.first = rows, u_start, u_end, first
        self.f_start, self.f_end = f_start, f_end
        self.pressures = pressures  # (Constant, start, end) of follower pressures
        self.rotations = rotations  # (NodeToSurface, start, end) of rotating obstacles

    def at(self, tau: float) -> tuple[np.ndarray, np.ndarray]:
        """Prescribed values and external forces at ``tau``; sets the follower pressures
        and the obstacles' rotations."""
        for constant, start, end in self.pressures:
            constant.value = start + tau * (end - start)
        for pair, start, end in self.rotations:
            pair.obstacle_rotation = start + tau * (end - start)
        return (self.u_start + tau * (self.u_end - self.u_start),
                self.f_start + tau * (self.f_end - self.f_start))


class Solver:
    """Drives a :class:`ContactProblem` through the steps of its scene."""

    def __init__(self, problem: ContactProblem, options_prefix: str = "dolfinx_friction_",
                 petsc_options: Optional[dict] = None,
                 reuse_factorisation: Optional[bool] = None):
        self.problem = problem
        self.comm, self.gdim = problem.comm, problem.gdim
        self.system = problem.system
        self.timers = self.system.timers
        self.newton = Newton(prefix=options_prefix, petsc_options=petsc_options,
                             reuse_factorisation=reuse_factorisation,
                             chord=problem.scene.solver.chord,
                             solve_statuses=problem.scene.solver.solve_statuses)
        self.summary = RunSummary(timers=self.timers)
        self._bc_state: dict[str, tuple] = {}
        self._load_state: dict[str, tuple] = {}
        self._rigid_state: dict[str, tuple] = {}
        self._unit_loads: dict[str, list] = {}
        self._reaction_rows = {g: problem.owned_group_dofs(g) for g in self.reaction_groups()}

    @property
    def linear(self):
        """The linear solver of the Newton iterations (its counts: factorisations...)."""
        return self.newton.linear

    def release(self) -> None:
        """Free the PETSc memory the run leaves (collective): the factorisations, and the
        objects dropped during it (:meth:`~dolfinx_friction.nls.newton.Newton.release`);
        counts, timers and fields stay, and a next :meth:`run` factorises afresh."""
        self.newton.release(self.system)

    # ------------------------------------------------------------ set-up
    def reaction_groups(self) -> list[str]:
        s = self.problem.scene
        if s.output.reactions is not None:
            return list(s.output.reactions)
        seen: dict[str, None] = {}
        for step in s.steps:
            seen.update(dict.fromkeys(bc.on for bc in step.bcs))
        return list(seen)

    def _loads(self, group: str) -> list:
        if group not in self._unit_loads:
            self._unit_loads[group] = [
                (self.problem.layout.owned_slice(f.block, self.gdim),
                 unit_loads(f, group), f)
                for f in self.problem.group_fields(group)]
        return self._unit_loads[group]

    def _step_loading(self, index: int) -> StepLoading:
        p, d = self.problem, self.gdim
        step = p.scene.steps[index]
        self._bc_state.update({bc.on: bc.u for bc in step.bcs})
        self._load_state.update({ld.on: (ld.traction, ld.pressure) for ld in step.loads})
        self._rigid_state.update({r.name: (r.displacement, r.force) for r in step.rigid})
        rotations = [(pair, np.asarray(p.scene.rotation_at(r.name, index, 0.0)),
                      np.asarray(r.rotation, float))
                     for r in step.rigid if r.rotation is not None
                     for pair in self._pairs_on(r.name)]
        # prescribed displacements (bcs that share nodes agree: scene.validation.check_bcs)
        n = p.layout.n_owned * d
        total, count = np.zeros(n), np.zeros(n)
        for group, comps in self._bc_state.items():
            rows = p.owned_group_dofs(group)
            for c, value in enumerate(comps):
                if value is not None:
                    np.add.at(total, rows[:, c], value)
                    np.add.at(count, rows[:, c], 1.0)
        f_end = np.zeros(n)
        for rigid in p.scene.rigids:
            disp, force = self._rigid_state.get(rigid.name, ((0.0,) * d, None))
            rows = p.rigid_dofs(rigid.name).ravel()
            if not len(rows):
                continue
            if force is not None:
                f_end[rows] += force
            else:
                total[rows] += disp
                count[rows] += 1.0
        mean = np.divide(total, count, out=np.zeros(n), where=count > 0)
        pressures = []
        for group, (traction, pressure) in self._load_state.items():
            for owned, unit, f in self._loads(group):
                vec = np.zeros(unit.shape[1])
                if traction is not None:  # a dead load: per reference area
                    vec += np.asarray(traction) @ unit[:d]
                follower = p.follower_pressures.get((f.body.name, group))
                if pressure is not None and follower is not None:
                    pressures.append((follower, float(follower.value), pressure))
                elif pressure is not None:
                    vec += pressure * unit[d]
                f_end[owned] += vec
        rows = np.flatnonzero(count > 0)
        u_start = self.system.x.getArray(readonly=True)[rows].copy()
        return StepLoading(rows, u_start, mean[rows], self.system.f_ext.copy(), f_end,
                           index == 0, pressures, rotations)

    def _pairs_on(self, rigid: str) -> list:
        """The contact pairs whose master is the obstacle ``rigid``."""
        p = self.problem
        return [p.pair_of(c) for c in p.scene.contacts if c.master == rigid]

    # -------------------------------------------------------------- run
    def run(self, on_increment: Optional[Callable[[Increment], None]] = None,
            control: Optional[RunControl] = None,
            max_increments: Optional[int] = None) -> RunSummary:
        """Solve every step; ``on_increment`` sees each converged increment.  ``control``
        (:mod:`~dolfinx_friction.scene.control`) is told the increment worked on and asked
        whether to stop at every residual evaluation.  ``max_increments``: stop after that
        many converged increments (the summary is then not ``converged``).  Raises
        :class:`ConvergenceError`."""
        if control is None:
            return self._run(on_increment, None, max_increments)

        # first in the guards: reached whatever the other guards find
        def guard() -> str:
            checkpoint(control, self.comm)
            return ""
        self.system.guards.insert(0, guard)
        try:
            return self._run(on_increment, control, max_increments)
        finally:
            self.system.guards.remove(guard)

    def _run(self, on_increment: Optional[Callable[[Increment], None]],
             control: Optional[RunControl], max_increments: Optional[int]) -> RunSummary:
        summary = self.summary
        start = time.perf_counter()
        try:
            self._steps(on_increment, control, max_increments, start)
            summary.converged = True
        except _Enough:
            pass
        summary.wall = time.perf_counter() - start
        summary.linear_solves = self._linear_solves()
        return summary

    def _steps(self, on_increment: Optional[Callable[[Increment], None]],
               control: Optional[RunControl], max_increments: Optional[int],
               start: float) -> None:
        summary = self.summary
        for index, step in enumerate(self.problem.scene.steps):
            loading = self._step_loading(index)
            newton = self.newton
            newton.rtol, newton.atol = step.newton_rtol, step.newton_atol
            newton.max_iterations, newton.line_search = step.max_iterations, step.line_search
            newton.stall = step.stall_iterations
            newton.convergence, newton.reaction_tol = step.convergence, step.reaction_tol
            done = [0]  # converged increments of this step

            def load(tau: float, loading=loading, index=index, done=done) -> None:
                if control is not None:
                    control.attempt(index, done[0] + 1)
                values, self.system.f_ext = loading.at(tau)
                self.system.prescribe(loading.rows, values)
                for pair in self.problem.pairs.values():
                    pair.ramp = (1.0 - tau) if loading.first else 0.0

            def converged(record: IncrementRecord, index=index, name=step.name,
                          done=done) -> None:
                summary.increments += 1
                summary.cutbacks += record.cutbacks
                summary.newton_iterations += record.work
                done[0] = record.number
                report = self._report(index, name, record, time.perf_counter() - start)
                if on_increment is not None:
                    on_increment(report)
                if max_increments is not None and summary.increments >= max_increments:
                    raise _Enough
            try:
                stepping.solve_steps(self.system, load, step.increments, newton,
                                     step.max_cutbacks, converged)
            except ConvergenceError as exc:
                summary.cutbacks += exc.cutbacks
                summary.newton_iterations += exc.iterations
                reason = (f"step {index} ({step.name!r}), increment {exc.increment} at "
                          f"t = {index + exc.t:.6g}: Newton did not converge after "
                          f"{step.max_cutbacks} cutbacks (last residual {exc.residual:.3e}"
                          + (f": {exc.reason})" if exc.reason else ")"))
                summary.failure = reason
                summary.wall = time.perf_counter() - start
                summary.linear_solves = self._linear_solves()
                raise ConvergenceError(reason, exc.increment, exc.t, exc.residual, exc.reason,
                                       exc.records, exc.cutbacks, exc.iterations) from None

    def _linear_solves(self) -> Optional[dict]:
        linear = self.linear
        return None if linear is None else {
            "preconditioner_setups": linear.factorisations,
            "krylov_iterations": linear.krylov_iterations,
            "condensed_solves": linear.condensed_solves,
            "contact_steps": linear.contact_steps,
            "chord_solves": linear.chord_solves}

    # ----------------------------------------------------------- reports
    def _report(self, index: int, name: str, record: IncrementRecord, wall: float) -> Increment:
        p, comm, system = self.problem, self.comm, self.system
        internal = system.internal
        # internal minus external force at a node: the force its constraint exerts on the body
        residual = internal - system.f_ext
        reactions = {g: comm.allreduce(residual[rows].sum(axis=0) if len(rows) else
                                       np.zeros(self.gdim))
                     for g, rows in self._reaction_rows.items()}
        u = system.x.getArray(readonly=True)
        rigid_u, rigid_f, rigid_m = {}, {}, {}
        for rigid in p.scene.rigids:
            rows = p.rigid_dofs(rigid.name).ravel()
            rigid_u[rigid.name] = comm.bcast(u[rows].copy() if comm.rank == 0 else None)
            rigid_f[rigid.name] = comm.bcast(internal[rows].copy() if comm.rank == 0 else None)
            rigid_m[rigid.name] = sum((np.atleast_1d(pair.obstacle_moment())
                                       for pair in self._pairs_on(rigid.name)),
                                      np.zeros(1 if self.gdim == 2 else 3))
        counts = [pair.counts() for pair in p.pairs.values()]
        active, slipping = (int(c) for c in np.sum(counts, axis=0)) if counts else (0, 0)
        trace = record.trace
        return Increment(index, name, record.number, index + record.t, trace.iterations,
                         trace.residuals[-1], trace.residuals, trace.status_changes,
                         trace.face_changes, trace.backtracks, active, slipping, wall,
                         reactions, rigid_u, rigid_f, rigid_m, record.penetration,
                         record.detached, record.imbalance, record.force, record.tolerance)

