"""Linear solves of the Newton iteration.

The default solver is MUMPS (unsymmetric LU) with the factorisation kept
(``reuse``): it preconditions GMRES for later Jacobians.  In small strain only the
contact part, supported on the contact surface, changes between iterations, so a few
Krylov iterations of back-solves replace a factorisation (1.46x faster at 67k dofs,
same Newton iterations: benchmarks/RESULTS.md).  It is refactorised when the matrix
pattern changes, and when GMRES does not converge within ``max_krylov`` iterations;
then the next :data:`PAUSE` Jacobians are factorised afresh as well (a stiff contact
change can need many Krylov iterations).  Keeping pays only where a factorisation costs
many back-solves: MUMPS's own counts (elimination flops RINFOG(3) against factor
entries INFOG(20)) decide, at least :data:`PAYBACK` back-solves; small 2D problems
factorise in milliseconds and are factorised every time.  A fresh factorisation is a
plain direct solve.  Every decision depends on counts, never on timings: runs are
repeatable.
A direct solve is checked: a factorisation that failed (a zero pivot) or a solution that
leaves a linear residual above :data:`SINGULAR` of the right-hand side means a singular
Jacobian (a body that only the contact held, and the contact opened): the solve fails
with that reason (:attr:`LinearSolver.failure`), and Newton with it.
``reuse=False`` factorises every Jacobian.  With user ``options`` (another solver) the
default is ``reuse=False``: their preconditioner is rebuilt for every Jacobian.  Only an
LU factorisation is kept (``reuse`` is ignored for other preconditioners); one by a
solver other than MUMPS is kept whatever it cost.
"""
from __future__ import annotations

from typing import Optional

from petsc4py import PETSc

from dolfinx_friction import compat

DIRECT = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}
REUSE = {"ksp_type": "gmres", "ksp_gmres_restart": 20, "ksp_rtol": 1e-12, "ksp_atol": 0.0,
         "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}  # max_it: ``max_krylov``
#: Jacobians factorised afresh after GMRES failed with a kept factorisation.
PAUSE = 3
#: Keep a factorisation only if it costs at least this many back-solves (in flops).
PAYBACK = 100
#: A direct solve whose linear residual exceeds this share of the right-hand side's norm
#: found no solution: the Jacobian is singular (measured on well-posed scenes: <= 1e-11).
SINGULAR = 1e-6


class LinearSolver:
    """Solves ``J x = b`` for a sequence of Jacobians, with PETSc options under ``prefix``."""

    def __init__(self, comm, prefix: str = "dolfinx_friction_", reuse: Optional[bool] = None,
                 options: Optional[dict] = None, max_krylov: int = 20):
        if reuse is None:
            reuse = options is None
        opts = PETSc.Options()
        for key, value in {**(REUSE if reuse else DIRECT), **(options or {})}.items():
            if not opts.hasName(prefix + key):
                opts[prefix + key] = value
        self.ksp = PETSc.KSP().create(comm)
        self.ksp.setOptionsPrefix(prefix)
        self.ksp.setFromOptions()
        pc = self.ksp.getPC()
        # only a factorisation is kept; only MUMPS reports what it cost
        self.reuse, self.max_krylov = reuse and pc.getType() == "lu", max_krylov
        self._counted = self.reuse and pc.getFactorSolverType() == "mumps"
        self._factored: Optional[PETSc.Mat] = None
        self._paused = 0  # Jacobians still to factorise afresh
        self._pays = False  # the last factorisation is worth keeping
        self.factorisations = 0
        self.krylov_iterations = 0
        #: why the last solve failed ("" if it did not)
        self.failure = ""

    def settings(self) -> dict:
        """The solver in use: ``ksp_type`` (``gmres`` on a kept factorisation, when one is
        kept), ``pc_type``, ``factor_solver_type`` (factorisations only),
        ``reuse_factorisation``."""
        pc = self.ksp.getPC()
        out = {"ksp_type": "gmres" if self.reuse else self.ksp.getType(),
               "pc_type": pc.getType()}
        if pc.getType() in ("lu", "cholesky", "ilu", "icc"):
            out["factor_solver_type"] = pc.getFactorSolverType()
        out["reuse_factorisation"] = self.reuse
        return out

    def solve(self, J: PETSc.Mat, b: PETSc.Vec, x: PETSc.Vec) -> bool:
        """Solve; returns False when the solver failed (:attr:`failure` says why)."""
        keep = self.reuse and self._pays and J is self._factored and not self._paused
        self._paused = max(self._paused - 1, 0)
        ok = self._attempt(J, b, x, keep)
        if ok or not keep:
            return ok
        self._paused = PAUSE
        return self._attempt(J, b, x, False)

    def _attempt(self, J, b, x, keep: bool) -> bool:
        """One solve, with the kept factorisation or a fresh one; whether it converged."""
        self.failure = ""
        if self.reuse:
            self.ksp.setType("gmres" if keep else "preonly")
            self.ksp.setTolerances(max_it=self.max_krylov)
        self.ksp.setOperators(J, J)
        self.ksp.getPC().setReusePreconditioner(keep)
        self.ksp.solve(b, x)
        if not keep:
            self.factorisations += 1
            self._factored = J
            self._pays = self.reuse and (not self._counted or _payback(
                self.ksp.getPC().getFactorMatrix()) >= PAYBACK)
        self.krylov_iterations += self.ksp.getIterationNumber()
        reason = self.ksp.getConvergedReason()
        if reason == compat.ksp_pc_failed():
            self.failure = "singular Jacobian (the factorisation met a zero pivot)"
        elif reason > 0 and self.ksp.getType() == "preonly":
            r = b.duplicate()
            J.mult(x, r)
            r.axpy(-1.0, b)
            residual, scale = r.norm(), b.norm()
            r.destroy()
            if not residual <= SINGULAR * scale:
                self.failure = (f"singular Jacobian (the linear residual is {residual:.2e} of "
                                f"{scale:.2e}: a body that nothing holds?)")
        elif reason <= 0:
            self.failure = f"the linear solver failed ({reason})"
        return reason > 0 and not self.failure


def _payback(F: PETSc.Mat) -> float:
    """Cost of a MUMPS factorisation in back-solves: flops over 4 x factor entries."""
    entries = F.getMumpsInfog(20)  # negative: millions
    entries = entries if entries >= 0 else -entries * 1e6
    return F.getMumpsRinfog(3) / (4.0 * max(entries, 1))
