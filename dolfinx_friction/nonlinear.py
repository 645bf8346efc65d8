"""Bodies given by the user's UFL residuals, coupled by contact, as one block system.

:class:`BlockProblem` joins one residual form ``F_i(u_i; v_i)`` per body into one
system: the unknown is one PETSc vector ``x`` (the bodies' owned dofs joined rank by
rank, as dolfinx joins blocks), the residual ``F(x)`` and Jacobian ``J(x)`` are dolfinx's
compiled assembly of every body plus the contact terms.  A body whose Jacobian does not
depend on its displacement (a linear form) is assembled once.  :class:`Newton` solves
one increment (line search, round-off floor, the kept factorisation of ``linear``);
:func:`solve_steps` drives increments with cutbacks and rollback of the friction
history; :func:`snes_solve` solves an increment with PETSc SNES instead.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Optional, Sequence

import numpy as np
import ufl
from petsc4py import PETSc

from dolfinx_friction import compat
from dolfinx_friction.assembly import CooPattern
from dolfinx_friction.fields import DofLayout
from dolfinx_friction.linear import LinearSolver
from dolfinx_friction.pair import ContactSetupError, NodeToSurface

#: Residual norms below this many round-off units of the terms they sum are converged.
ROUNDOFF_FLOOR = 2 * np.finfo(float).eps


def _is_linear(jacobian: ufl.Form, u) -> bool:
    """Whether a Jacobian form does not depend on ``u`` (its body is linear)."""
    from ufl.algorithms import expand_derivatives
    return not expand_derivatives(ufl.derivative(jacobian, u)).integrals()


class _Body:
    """One block: compiled residual and Jacobian, its vector and matrix, its bcs."""

    def __init__(self, F: ufl.Form, u, J: Optional[ufl.Form], bcs: Sequence):
        V = u.function_space
        J = J if J is not None else ufl.derivative(F, u)
        self.u, self.V, self.bcs = u, V, list(bcs)
        self.linear = _is_linear(J, u)
        self.F, self.J = compat.form(F), compat.form(J)
        self.b = compat.petsc_vector(compat.function(V)).duplicate()
        self.A = compat.create_matrix(self.J)
        self.n_owned = V.dofmap.index_map.size_local * V.dofmap.index_map_bs

    def jacobian_values(self) -> np.ndarray:
        """CSR values of the body's Jacobian at its current ``u`` (bcs as dolfinx sets them)."""
        self.A.zeroEntries()
        compat.assemble_matrix_into(self.A, self.J, self.bcs)
        return self.A.getValuesCSR()[2]


class BlockProblem:
    """Residual and Jacobian of several bodies with contact, in one block numbering.

    Parameters
    ----------
    residuals : one UFL residual form per body, ``F_i(u_i; v_i)`` (internal minus
        external virtual work), linear in the test function.
    u : the bodies' displacement Functions (vector Lagrange spaces of the mesh dimension);
        their values are the initial guess and, after a solve, the solution.
    bcs : dolfinx DirichletBCs of any of the bodies' spaces.
    contacts : :class:`NodeToSurface` pairs built with ``spaces`` = the bodies' spaces in
        this order (the default for a pair whose slave and master are the first bodies).
    jacobians : optional Jacobian forms per body (None: ``ufl.derivative(F_i, u_i)``).
    """

    def __init__(self, residuals: Sequence[ufl.Form], u: Sequence, bcs: Sequence = (),
                 contacts: Sequence[NodeToSurface] = (),
                 jacobians: Optional[Sequence[Optional[ufl.Form]]] = None):
        if len(residuals) != len(u):
            raise ContactSetupError(f"{len(residuals)} residual forms for {len(u)} bodies")
        self.spaces = [w.function_space for w in u]
        for c in contacts:
            if len(c.spaces) != len(self.spaces) or any(
                    a is not b for a, b in zip(c.spaces, self.spaces)):
                raise ContactSetupError(f"{c.name}: built on other spaces than the problem's "
                                        f"bodies (pass spaces=[...] in the bodies' order)")
        jacobians = jacobians or [None] * len(u)
        self.bcs, self.contacts = list(bcs), list(contacts)
        self.bodies = [_Body(F, w, J, [bc for bc in bcs if compat.bc_on_space(bc, w.function_space)])
                       for F, w, J in zip(residuals, u, jacobians)]
        V0 = self.spaces[0]
        self.comm = V0.mesh.comm
        self.gdim = V0.mesh.geometry.dim
        for V in self.spaces:
            if V.dofmap.index_map_bs != self.gdim:
                raise ContactSetupError("every body needs a vector space of the mesh dimension")
        self.layout = DofLayout(self.comm, [V.dofmap.index_map for V in self.spaces], 0)
        n = self.layout.n_owned * self.gdim
        self.x = PETSc.Vec().createMPI((n, PETSc.DETERMINE), comm=self.comm)
        self.b = self.x.duplicate()
        self.gather()
        self._base = self._bulk_pattern()
        self._linear_data = {k: self._base.gather_values(k, body.jacobian_values())
                             for k, body in enumerate(self.bodies) if body.linear}
        self._pattern: Optional[CooPattern] = None
        self._versions: Optional[list[int]] = None
        self._J: Optional[PETSc.Mat] = None
        self._J_abs: Optional[PETSc.Mat] = None
        self._data = np.zeros(0)

    @property
    def linear(self) -> bool:
        """Whether every body is linear (only the contact changes the Jacobian)."""
        return all(b.linear for b in self.bodies)

    # ------------------------------------------------------------ numbering
    def _slice(self, k: int) -> slice:
        return self.layout.owned_slice(k, self.gdim)

    def scatter(self, x: Optional[PETSc.Vec] = None) -> None:
        """Copy the block vector (default :attr:`x`) into the bodies' Functions."""
        values = (x or self.x).getArray(readonly=True)
        for k, body in enumerate(self.bodies):
            body.u.x.array[: body.n_owned] = values[self._slice(k)]
            compat.scatter_forward(body.u)

    def gather(self) -> None:
        """Copy the bodies' Functions into :attr:`x`."""
        values = self.x.getArray()
        for k, body in enumerate(self.bodies):
            values[self._slice(k)] = body.u.x.array[: body.n_owned]
        self.x.setArray(values)

    def apply_bcs(self) -> None:
        """Write the current values of the Dirichlet conditions into :attr:`x`."""
        self.scatter()
        for body in self.bodies:
            compat.set_bc_values(compat.petsc_vector(body.u), body.bcs)
            compat.scatter_forward(body.u)
        self.gather()

    def _bulk_pattern(self) -> CooPattern:
        d = self.gdim
        blocks = []
        for k, body in enumerate(self.bodies):
            compat.assemble_matrix_into(body.A, body.J, body.bcs)
            indptr, cols, _ = body.A.getValuesCSR()
            rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
            cols = cols.astype(np.int64)
            blocks.append((self.layout.nodes(k)[rows // d] * d + rows % d,
                           self.layout.from_block_global(k, cols // d) * d + cols % d))
        return CooPattern(self.comm, self.layout.n_owned * d, blocks)

    # ------------------------------------------------------------ assembly
    def residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """``b = F(x)``: the bodies' residuals (``x - g`` on Dirichlet rows) plus the
        contact forces at their last :meth:`NodeToSurface.update`."""
        self.scatter(x)
        values = b.getArray()
        for k, body in enumerate(self.bodies):
            compat.assemble_residual_into(body.b, body.F, body.J, body.bcs,
                                          compat.petsc_vector(body.u))
            values[self._slice(k)] = body.b.getArray(readonly=True)[: body.n_owned]
        b.setArray(values)
        for c in self.contacts:
            c.add_residual(b, self.bcs)

    def matrix(self) -> PETSc.Mat:
        """The Jacobian matrix for the current contact couplings (a new one when they
        changed since the last call; collective)."""
        versions = [c.couplings_version for c in self.contacts]
        if self._J is None or versions != self._versions:
            self._pattern = self._base.extended([c.couplings() for c in self.contacts])
            for M in (self._J, self._J_abs):
                if M is not None:
                    M.destroy()
            self._J = self._pattern.create_matrix(self.gdim)
            self._J_abs = None
            for c in self.contacts:
                c.register_matrix(self._J)
            self._versions = versions
        return self._J

    def jacobian(self, x: PETSc.Vec, A: Optional[PETSc.Mat] = None) -> PETSc.Mat:
        """Fill the Jacobian at ``x`` (the contacts at their last update) into ``A``
        (default :meth:`matrix`); returns it."""
        A = A or self.matrix()
        self.scatter(x)
        base = np.zeros(self._base.nnz)
        for k, body in enumerate(self.bodies):
            base += (self._linear_data[k] if body.linear
                     else self._base.gather_values(k, body.jacobian_values()))
        data = self._pattern.from_base(base)
        for k, c in enumerate(self.contacts):
            data += self._pattern.gather_values(k, c.coupling_values(self.bcs))
        self._pattern.fill(A, data)
        self._data = data
        return A

    def roundoff_scale(self, x: PETSc.Vec) -> float:
        """``2 eps || |J| |x| ||``: the size of the round-off in the residual, from the
        last Jacobian (collective)."""
        if self._J_abs is None:
            self._J_abs = self._pattern.create_matrix(self.gdim)
        self._pattern.fill(self._J_abs, np.abs(self._data))
        ax, out = x.duplicate(), x.duplicate()
        x.copy(ax)
        ax.abs()
        self._J_abs.mult(ax, out)
        scale = out.norm()
        ax.destroy()
        out.destroy()
        return ROUNDOFF_FLOOR * scale


@dataclass
class NewtonResult:
    """One Newton solve: ``residuals[k]`` is the residual norm at iterate k."""

    converged: bool
    residuals: list[float] = field(default_factory=list)
    backtracks: list[int] = field(default_factory=list)

    @property
    def iterations(self) -> int:
        return len(self.backtracks)


class Newton:
    """Newton's method for a :class:`BlockProblem` increment.

    Converged when the residual norm is below ``max(rtol r_0, atol)`` or below the
    round-off floor of its terms.  With ``line_search`` the step is halved (up to 5
    times) while the residual norm does not decrease.  The linear solver is
    :class:`~dolfinx_friction.linear.LinearSolver` (MUMPS; options under ``prefix``).
    """

    def __init__(self, rtol: float = 1e-9, atol: float = 1e-10, max_iterations: int = 30,
                 line_search: bool = True, prefix: str = "dolfinx_friction_newton_",
                 petsc_options: Optional[dict] = None,
                 reuse_factorisation: Optional[bool] = None):
        self.rtol, self.atol, self.max_iterations = rtol, atol, max_iterations
        self.line_search = line_search
        self.prefix, self.petsc_options = prefix, petsc_options
        self.reuse_factorisation = reuse_factorisation
        self._linear: Optional[LinearSolver] = None

    def _solver(self, problem: BlockProblem) -> LinearSolver:
        if self._linear is None:
            reuse = self.reuse_factorisation
            if reuse is None and self.petsc_options is None:
                reuse = problem.linear  # a kept factorisation pays where only contact changes
            self._linear = LinearSolver(problem.comm, self.prefix, reuse, self.petsc_options)
        return self._linear

    def _evaluate(self, problem: BlockProblem, pairing: bool) -> float:
        for c in problem.contacts:
            c.update(problem.x, pairing=pairing)
        problem.residual(problem.x, problem.b)
        return problem.b.norm()

    def _line_search(self, problem: BlockProblem, dx: PETSc.Vec, norm0: float,
                     target: float) -> int:
        """Halve the step ``x <- x - dx`` while the residual (at the frozen pairing) does
        not decrease and is not converged; returns the halvings."""
        alpha = 1.0
        for halvings in range(5):
            norm = self._evaluate(problem, False)
            if norm <= max((1.0 - 1e-4 * alpha) * norm0, target):
                return halvings
            alpha *= 0.5
            problem.x.axpy(alpha, dx)  # back from x - 2 alpha dx to x - alpha dx
        return 5

    def solve(self, problem: BlockProblem) -> NewtonResult:
        """Newton iterations from :attr:`BlockProblem.x` (contacts already begun)."""
        x, b = problem.x, problem.b
        dx = x.duplicate()
        out = NewtonResult(False)
        floor = 0.0
        for it in range(self.max_iterations + 1):
            norm = self._evaluate(problem, True)  # pairing at the accepted iterate
            out.residuals.append(norm)
            if not np.isfinite(norm):
                break
            target = max(self.rtol * out.residuals[0], self.atol)
            if norm <= max(target, floor):
                out.converged = True
                break
            if it == self.max_iterations:
                break
            A = problem.jacobian(x)
            if norm < 1e-4 * out.residuals[0]:
                floor = problem.roundoff_scale(x)
                if norm <= floor:
                    out.converged = True
                    break
            if not self._solver(problem).solve(A, b, dx):
                out.backtracks.append(0)
                break
            x.axpy(-1.0, dx)
            out.backtracks.append(self._line_search(problem, dx, norm, max(target, floor))
                                  if self.line_search else 0)
        dx.destroy()
        problem.scatter()
        return out


@dataclass
class IncrementRecord:
    """A converged increment of :func:`solve_steps`."""

    t: float  # pseudo-time reached, in (0, 1]
    iterations: int
    residuals: list[float]


class ConvergenceError(RuntimeError):
    """An increment failed after all cutbacks."""


def solve_steps(problem: BlockProblem, load: Callable[[float], None], increments: int = 1,
                newton: Optional[Newton] = None, max_cutbacks: int = 6,
                on_increment: Optional[Callable[[IncrementRecord], None]] = None
                ) -> list[IncrementRecord]:
    """Ramp a load from pseudo-time 0 to 1 in ``increments`` equal increments.

    ``load(t)`` sets everything prescribed at ``t`` (the values of the Dirichlet
    conditions' Functions or Constants, obstacle translations, load Constants).  A failed
    increment is retried at half the size (history rolled back) up to ``max_cutbacks``
    times; the size grows back after easy increments.  The displacement rate of the last
    increment predicts the next one.  Raises :class:`ConvergenceError`.
    """
    newton = newton or Newton()
    x = problem.x
    x_n, rate = x.duplicate(), None
    records: list[IncrementRecord] = []
    t, level = 0.0, 0
    while t < 1.0 - 1e-12:
        dt = min(1.0 / (increments * 2 ** level), 1.0 - t)
        x.copy(x_n)
        load(t + dt)
        if rate is not None:
            x.axpy(dt, rate)
        problem.apply_bcs()
        for c in problem.contacts:
            c.begin(x, start=x_n)
        result = newton.solve(problem)
        if not result.converged:
            for c in problem.contacts:
                c.rollback()
            x_n.copy(x)
            problem.scatter()
            level += 1
            if level > max_cutbacks:
                raise ConvergenceError(f"increment to t = {t + dt:.6g} did not converge after "
                                       f"{max_cutbacks} cutbacks (last residual "
                                       f"{result.residuals[-1]:.3e})")
            continue
        for c in problem.contacts:
            c.commit()
        rate = rate or x.duplicate()
        rate.waxpy(-1.0, x_n, x)
        rate.scale(1.0 / dt)
        t += dt
        if level and result.iterations <= 4:
            level -= 1
        record = IncrementRecord(t, result.iterations, result.residuals)
        records.append(record)
        if on_increment is not None:
            on_increment(record)
    return records


def snes_solve(problem: BlockProblem, prefix: str = "dolfinx_friction_snes_",
               options: Optional[dict] = None) -> int:
    """Solve an increment with PETSc SNES (``newtonls`` unless the options say otherwise;
    every SNES/KSP option and monitor under ``prefix`` applies).  The contacts must have
    begun; they are paired at every residual evaluation, without a new search (the
    couplings stay those of :meth:`BlockProblem.matrix`).  Returns SNES's converged
    reason (> 0: converged)."""
    opts = PETSc.Options()
    defaults = {"snes_type": "newtonls", "snes_linesearch_type": "bt", "ksp_type": "preonly",
                "pc_type": "lu", "pc_factor_mat_solver_type": "mumps", "snes_rtol": 1e-9,
                "snes_atol": 1e-10}
    for key, value in {**defaults, **(options or {})}.items():
        if not opts.hasName(prefix + key):
            opts[prefix + key] = value
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
    snes.solve(None, problem.x)
    reason = snes.getConvergedReason()
    snes.destroy()
    problem.scatter()
    return reason
