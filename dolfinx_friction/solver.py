"""Load stepping with cutbacks, and Newton's method on the block system.

Each step ramps prescribed displacements, loads and rigid-obstacle motions
linearly from their values at the start of the step to the step's totals.
An increment whose Newton iteration fails is halved (up to ``max_cutbacks``
times) after the displacement and the contact history are rolled back; the
history is committed only on convergence.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx_friction.assembly import CooPattern
from dolfinx_friction.linear import LinearSolver
from dolfinx_friction.problem import ContactProblem, ModelError, Timers

#: The residual is converged once it is below this many round-off units of the terms it
#: sums (|K| |u| + |f_ext| + the contact forces' sensitivity to the coordinates): Newton
#: cannot reduce it further, whatever the tolerances ask.
ROUNDOFF_FLOOR = 2 * np.finfo(float).eps


class ConvergenceError(RuntimeError):
    """An increment failed after all cutbacks."""


@dataclass
class NewtonTrace:
    """Per-iteration record of one Newton solve: ``residuals[k]`` is the residual norm at
    iterate k; in iteration k + 1, ``status_changes[k]`` slave nodes changed their contact
    status (open, stick, slip), ``face_changes[k]`` others only their master face, and the
    line search halved the step ``backtracks[k]`` times."""

    residuals: list[float] = field(default_factory=list)
    status_changes: list[int] = field(default_factory=list)
    face_changes: list[int] = field(default_factory=list)
    backtracks: list[int] = field(default_factory=list)

    @property
    def iterations(self) -> int:
        return len(self.backtracks)


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
    backtracks: list[int]  # per iteration: line-search halvings
    active: int
    slipping: int
    wall: float
    reactions: dict[str, np.ndarray]
    rigid_u: dict[str, np.ndarray]
    rigid_f: dict[str, np.ndarray]
    penetration: dict[str, float]  # largest overclosure / slave spacing, per contact pair
    detached: dict[str, int]  # nodes in contact before that slid off the master surface


@dataclass
class RunSummary:
    increments: int = 0
    cutbacks: int = 0
    newton_iterations: int = 0
    converged: bool = False
    wall: float = 0.0
    timers: Timers = field(default_factory=Timers)
    failure: str = ""


def _dofs(nodes: np.ndarray, gdim: int) -> np.ndarray:
    """Scalar dofs (n, nodes*gdim) of elements given by their system nodes (n, nodes)."""
    return (nodes[:, :, None] * gdim + np.arange(gdim)).reshape(len(nodes), nodes.shape[1] * gdim)


class _Loading:
    """Prescribed values of one step: constrained rows and ramped external forces."""

    def __init__(self, rows: np.ndarray, u_start, u_end, f_start, f_end, first: bool):
        self.rows, self.u_start, self.u_end, self.first = rows, u_start, u_end, first
        self.f_start, self.f_end = f_start, f_end

    def at(self, tau: float) -> tuple[np.ndarray, np.ndarray]:
        return (self.u_start + tau * (self.u_end - self.u_start),
                self.f_start + tau * (self.f_end - self.f_start))


class _IncrementSize:
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


class Solver:
    """Drives a :class:`ContactProblem` through the steps of its scene."""

    def __init__(self, problem: ContactProblem, options_prefix: str = "dolfinx_friction_",
                 petsc_options: Optional[dict] = None,
                 reuse_factorisation: Optional[bool] = None):
        self.problem = problem
        p = problem
        self.comm, self.gdim = p.comm, p.gdim
        self.timers = Timers()
        self.linear = LinearSolver(p.comm, options_prefix, reuse_factorisation, petsc_options)
        self.u_n = p.u.duplicate()
        self.R = p.u.duplicate()
        self.S = p.u.duplicate()  # round-off scale of the residual's rows
        self._abs_u = p.u.duplicate()
        self._K_abs = _absolute(p.K_bulk)
        self._modes = p.rigid_body_modes()
        self.du = p.u.duplicate()
        self.f_ext = np.zeros(p.layout.n_owned * self.gdim)
        self._pattern: Optional[CooPattern] = None
        self._bc_slots: Optional[tuple] = None  # (bc rows, their slots in the pattern)
        self._pairs: list = []
        self._J: Optional[PETSc.Mat] = None
        self._bc_state: dict[str, tuple] = {}
        self._load_state: dict[str, tuple] = {}
        self._rigid_state: dict[str, tuple] = {}
        self._unit_loads: dict[str, list] = {}
        self._reaction_rows = {g: p.owned_group_dofs(g) for g in self.reaction_groups()}
        rigid_rows = [p.rigid_dofs(r.name).ravel() for r in p.scene.rigids]
        self._rigid_rows = np.concatenate(rigid_rows) if rigid_rows else np.zeros(0, int)
        self._free_rigid_rows = np.zeros(0, dtype=np.int64)
        diagonal = p.K_bulk.getDiagonal()
        self._rigid_spring = 1e-12 * self.comm.allreduce(diagonal.norm(PETSc.NormType.INFINITY),
                                                         op=MPI.MAX)
        diagonal.destroy()

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
            from dolfinx_friction import bulk
            self._unit_loads[group] = [
                (self.problem.layout.owned_slice(f.block, self.gdim), bulk.unit_loads(f, group))
                for f in self.problem.group_fields(group)]
        return self._unit_loads[group]

    def validate_steps(self) -> None:
        """Check the prescribed values of every step before solving anything (collective)."""
        saved = (dict(self._bc_state), dict(self._load_state), dict(self._rigid_state))
        try:
            for index in range(len(self.problem.scene.steps)):
                self._step_loading(index)
        finally:
            self._bc_state, self._load_state, self._rigid_state = saved

    def _report_conflict(self, index: int, conflict: np.ndarray) -> None:
        """Name the bc groups that prescribe different values to the same components."""
        found = set()
        for group, comps in self._bc_state.items():
            rows = self.problem.owned_group_dofs(group)
            for c, value in enumerate(comps):
                if value is not None and conflict[rows[:, c]].any():
                    found.add((group, "xyz"[c]))
        found = sorted(set().union(*self.comm.allgather(found)))
        groups = sorted({g for g, _ in found})
        axes = "".join(sorted({a for _, a in found}))
        raise ModelError(f"step.{index}: bc groups {', '.join(map(repr, groups))} overlap and "
                         f"prescribe different values of component(s) {axes} to shared nodes")

    def _step_loading(self, index: int) -> _Loading:
        p, d = self.problem, self.gdim
        step = p.scene.steps[index]
        self._bc_state.update({bc.on: bc.u for bc in step.bcs})
        self._load_state.update({ld.on: (ld.traction, ld.pressure) for ld in step.loads})
        self._rigid_state.update({r.name: (r.displacement, r.force) for r in step.rigid})
        # prescribed displacements: sums and counts per dof detect conflicting values
        n = p.layout.n_owned * d
        total, total_sq, count = np.zeros(n), np.zeros(n), np.zeros(n)
        for group, comps in self._bc_state.items():
            rows = p.owned_group_dofs(group)
            for c, value in enumerate(comps):
                if value is not None:
                    np.add.at(total, rows[:, c], value)
                    np.add.at(total_sq, rows[:, c], value * value)
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
        spread = np.divide(total_sq, count, out=np.zeros(n), where=count > 0) - mean ** 2
        conflict = spread > 1e-24 * np.maximum(1.0, mean ** 2)
        if self.comm.allreduce(int(conflict.any())):
            self._report_conflict(index, conflict)
        for group, (traction, pressure) in self._load_state.items():
            for owned, unit in self._loads(group):
                vec = np.zeros(unit.shape[1])
                if traction is not None:
                    vec += np.asarray(traction) @ unit[:d]
                if pressure is not None:
                    vec += pressure * unit[d]
                f_end[owned] += vec
        rows = np.flatnonzero(count > 0)
        self._free_rigid_rows = np.setdiff1d(self._rigid_rows, rows)
        u_start = self.problem.u.getArray(readonly=True)[rows].copy()
        return _Loading(rows, u_start, mean[rows], self.f_ext.copy(), f_end, index == 0)

    # -------------------------------------------------------------- run
    def run(self, on_increment: Optional[Callable[[Increment], None]] = None) -> RunSummary:
        summary = self.summary = RunSummary(timers=self.timers)
        start = time.perf_counter()
        for index, step in enumerate(self.problem.scene.steps):
            loading = self._step_loading(index)
            tau, number, size = 0.0, 0, _IncrementSize(step.increments)
            rate = None  # du/dtau of the step's last increment: the next one's predictor
            while tau < 1.0 - 1e-12:
                dtau = min(size.current, 1.0 - tau)
                saved = self._save()
                if rate is not None:
                    self.problem.u.axpy(dtau, rate)
                ok, trace = self._newton(step, loading, tau + dtau)
                summary.newton_iterations += trace.iterations
                if ok and size.level < step.max_cutbacks and self._contact_vanished():
                    ok = False  # too coarse to tell a slide off the master from a lost contact
                if not ok:
                    self._restore(saved)
                    size.failed()
                    summary.cutbacks += 1
                    if size.level > step.max_cutbacks:
                        reason = (f"step {index} ({step.name!r}), increment {number + 1} at "
                                  f"t = {index + tau:.6g}: Newton did not converge after "
                                  f"{step.max_cutbacks} cutbacks (last residual "
                                  f"{trace.residuals[-1]:.3e})")
                        summary.failure = reason
                        summary.wall = time.perf_counter() - start
                        raise ConvergenceError(reason)
                    continue
                tau += dtau
                number += 1
                size.converged(trace.iterations)
                rate = rate or self.problem.u.duplicate()
                rate.waxpy(-1.0, self.u_n, self.problem.u)
                rate.scale(1.0 / dtau)
                report = self._report(index, step.name, number, index + tau, trace,
                                      time.perf_counter() - start)
                for inter in self.problem.interactions:
                    inter.commit()
                summary.increments += 1
                if on_increment is not None:
                    on_increment(report)
        summary.converged = True
        summary.wall = time.perf_counter() - start
        return summary

    def _contact_vanished(self) -> bool:
        """Whether a pair that had closed nodes at the last commit has none, with some of
        them slid off the master surface (collective).  A whole contact zone leaving the
        master in one increment is more often a diverging iterate that threw it away than
        a real slide off the end: the increment is cut back, and accepted (with the warning)
        only at the last cutback level."""
        for inter in self.problem.interactions:
            before, now, off = self.comm.allreduce(
                np.array([inter.closed.sum(), inter.counts()[0], inter.detached()]))
            if before > 0 and now == 0 and off > 0:
                return True
        return False

    def _save(self):
        self.problem.u.copy(self.u_n)
        return self.f_ext.copy(), [inter.save() for inter in self.problem.interactions]

    def _restore(self, saved) -> None:
        self.u_n.copy(self.problem.u)
        self.f_ext = saved[0].copy()
        for inter, s in zip(self.problem.interactions, saved[1]):
            inter.restore(s)

    # ------------------------------------------------------------ Newton
    def _newton(self, step, loading: _Loading, tau: float) -> tuple[bool, NewtonTrace]:
        p = self.problem
        values, self.f_ext = loading.at(tau)
        self._ramp = (1.0 - tau) if loading.first else 0.0
        u_local = p.u.getArray()
        u_local[loading.rows] = values
        p.u.setArray(u_local)
        trace = NewtonTrace()
        state = None
        for it in range(step.max_iterations + 1):
            norm = self._assemble(it, loading.rows)
            trace.residuals.append(norm)
            if state is not None:
                self._record_changes(state, trace)
            state = [inter.contact_state() for inter in p.interactions]
            if not np.isfinite(norm):
                return False, trace
            target = max(step.newton_rtol * trace.residuals[0], step.newton_atol)
            if norm <= max(target, self._floor):
                return True, trace
            if it == step.max_iterations:
                return False, trace
            t0 = time.perf_counter()
            solved = self.linear.solve(self._J, self.R, self.du)
            self.timers.add("linear_solve", time.perf_counter() - t0)
            if not solved:
                trace.backtracks.append(0)
                return False, trace
            p.u.axpy(-1.0, self.du)
            trace.backtracks.append(self._line_search(it, loading.rows, norm, target)
                                    if step.line_search else 0)
        return False, trace

    def _record_changes(self, before: list[np.ndarray], trace: NewtonTrace) -> None:
        """Count (all ranks) the slave nodes whose status, or else only master face, differs
        from ``before``."""
        counts = np.zeros(2, dtype=np.int64)
        for inter, old in zip(self.problem.interactions, before):
            differs = inter.contact_state() != old
            counts += differs[:, 0].sum(), (differs[:, 1] & ~differs[:, 0]).sum()
        status, face = self.comm.allreduce(counts)
        trace.status_changes.append(int(status))
        trace.face_changes.append(int(face))

    def _line_search(self, it: int, rows: np.ndarray, norm0: float, target: float) -> int:
        """Backtrack along the Newton step while the residual norm does not decrease (and
        is not converged: at round-off it need not decrease); returns the halvings."""
        alpha = 1.0
        for halvings in range(5):
            norm = self._assemble(it, rows, jacobian=False)
            if norm <= max((1.0 - 1e-4 * alpha) * norm0, target, self._floor):
                return halvings
            alpha *= 0.5
            self.problem.u.axpy(alpha, self.du)  # back from u - 2 alpha du to u - alpha du
        return 5

    def _assemble(self, it: int, bc_rows: np.ndarray, jacobian: bool = True) -> float:
        """Residual (and Jacobian) at the current iterate; returns the residual norm."""
        p, d = self.problem, self.gdim
        t0 = time.perf_counter()
        p.K_bulk.mult(p.u, self.R)
        r = self.R.getArray()
        r -= self.f_ext
        self.R.setArray(r)
        p.u.copy(self._abs_u)
        self._abs_u.abs()
        self._K_abs.mult(self._abs_u, self.S)
        self.S.setArray(self.S.getArray() + np.abs(self.f_ext))
        self.timers.add("bulk_assembly", time.perf_counter() - t0)
        t0 = time.perf_counter()
        if jacobian and it == 0:
            p.update_fields()  # the search reads master faces and slave areas from the bodies
        vals = []
        for k, inter in enumerate(p.interactions):
            if jacobian and it < inter.pairing_iterations:
                ts = time.perf_counter()
                self._pair(k, inter, it)
                self.timers.add("contact_search", time.perf_counter() - ts)
            el = inter.evaluate(p.u, self.u_n, self._ramp)
            dofs = _dofs(el.nodes, d).ravel().astype(PETSc.IntType)
            self.R.setValues(dofs, el.result.f.ravel(), addv=PETSc.InsertMode.ADD)
            self.S.setValues(dofs, el.roundoff.ravel(), addv=PETSc.InsertMode.ADD)
            if jacobian:  # tangents into the slots of the pair's candidate elements
                nd = el.nodes.shape[1] * d
                block = np.zeros((len(inter.candidates.slave), nd, nd))
                block[el.candidate] = el.result.K.reshape(-1, nd, nd)
                vals.append(block.ravel())
        self.R.assemble()
        self.S.assemble()
        self.timers.add("contact_assembly", time.perf_counter() - t0)
        r = self.R.getArray()
        self._internal = r + self.f_ext  # for reactions and rigid forces
        r[bc_rows] = 0.0
        self.R.setArray(r)
        scale = self.S.getArray(readonly=True).copy()
        scale[bc_rows] = 0.0
        self._floor = ROUNDOFF_FLOOR * np.sqrt(self.comm.allreduce(float(scale @ scale)))
        if jacobian:
            t0 = time.perf_counter()
            self._fill_jacobian(vals, bc_rows)
            self.timers.add("contact_assembly", time.perf_counter() - t0)
        return self.R.norm()

    def _pair(self, k: int, inter, it: int) -> None:
        """Search (first iteration) and pair; search again (collective) if a slave node
        slid past all its candidate faces."""
        p = self.problem
        if it == 0:
            inter.search(p.u, p.master_displacements(k))
        inter.pair(p.u, it)
        if it > 0 and self.comm.allreduce(int(inter.needs_search())):
            p.update_fields()
            inter.search(p.u, p.master_displacements(k), update_areas=False)
            inter.pair(p.u, it)
        inter.mark_off_surface()

    def _fill_jacobian(self, vals: list, bc_rows: np.ndarray) -> None:
        """Bulk stiffness + contact tangents; the pattern holds all candidate couplings and is
        rebuilt only when the candidates change (at most once per increment)."""
        p = self.problem
        vals = np.concatenate(vals) if vals else np.zeros(0)
        pairs = [i.candidates.nodes for i in p.interactions]
        same = (self._pattern is not None and len(pairs) == len(self._pairs)
                and all(np.array_equal(a, b) for a, b in zip(pairs, self._pairs)))
        if self.comm.allreduce(0 if same else 1) > 0:
            dofs = [_dofs(nodes, self.gdim) for nodes in pairs]
            rows = np.concatenate([np.repeat(x, x.shape[1], axis=1).ravel() for x in dofs]
                                  + [np.zeros(0, np.int64)])
            cols = np.concatenate([np.tile(x, (1, x.shape[1])).ravel() for x in dofs]
                                  + [np.zeros(0, np.int64)])
            self._pattern = p.bulk_pattern.extended([(rows, cols)])
            self._bulk_data = self._pattern.from_base(p.bulk_data)
            if self._J is not None:
                self._J.destroy()
            self._J = self._pattern.create_matrix(self.gdim)
            self._J.setNearNullSpace(self._modes)  # for multigrid; direct solvers ignore it
            self._pairs = [a.copy() for a in pairs]
            self._bc_slots = None
        if self._bc_slots is None or self._bc_slots[0] is not bc_rows:  # new pattern or step
            self._bc_slots = (bc_rows, self._pattern.row_slots(bc_rows))
        data = self._bulk_data + self._pattern.gather_values(0, vals)
        data[self._bc_slots[1]] = 0.0
        data[self._pattern.diagonal_slots[bc_rows]] = 1.0
        # A force-controlled obstacle may have no stiffness along some axis (a frictionless
        # plane in its own plane): a tiny spring in the Jacobian only keeps the matrix regular,
        # the residual, hence the solution, is unchanged.
        data[self._pattern.diagonal_slots[self._free_rigid_rows]] += self._rigid_spring
        self._pattern.fill(self._J, data)

    # ----------------------------------------------------------- reports
    def _report(self, index, name, number, t, trace: NewtonTrace, wall) -> Increment:
        p, comm = self.problem, self.comm
        internal = self._internal
        # internal minus external force at a node: the force its constraint exerts on the body
        residual = internal - self.f_ext
        reactions = {g: comm.allreduce(residual[rows].sum(axis=0) if len(rows) else
                                       np.zeros(self.gdim))
                     for g, rows in self._reaction_rows.items()}
        u = p.u.getArray(readonly=True)
        rigid_u, rigid_f = {}, {}
        for rigid in p.scene.rigids:
            rows = p.rigid_dofs(rigid.name).ravel()
            rigid_u[rigid.name] = comm.bcast(u[rows].copy() if comm.rank == 0 else None)
            rigid_f[rigid.name] = comm.bcast(internal[rows].copy() if comm.rank == 0 else None)
        counts = np.sum([i.counts() for i in p.interactions], axis=0) if p.interactions else (0, 0)
        active, slipping = (int(c) for c in comm.allreduce(np.asarray(counts)))
        penetration = {i.name: comm.allreduce(i.penetration(), op=MPI.MAX)
                       for i in p.interactions}
        detached = {i.name: comm.allreduce(i.detached()) for i in p.interactions}
        return Increment(index, name, number, t, trace.iterations, trace.residuals[-1],
                         trace.residuals, trace.status_changes, trace.face_changes,
                         trace.backtracks, active, slipping,
                         wall, reactions, rigid_u, rigid_f, penetration, detached)


def _absolute(A: PETSc.Mat) -> PETSc.Mat:
    """A copy of ``A`` with the absolute values of its entries."""
    B = A.duplicate(copy=True)
    indptr, indices, values = B.getValuesCSR()
    B.setValuesCSR(indptr, indices, np.abs(values))
    B.assemble()
    return B
