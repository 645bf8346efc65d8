"""Linear solves of the Newton iteration.

By default every Newton iteration factorises the Jacobian with MUMPS (unsymmetric
LU).  With ``reuse=True`` a factorisation is kept and used as the preconditioner of
GMRES for later Jacobians: in small strain only the contact part, supported on the
contact surface, changes between iterations, so a few Krylov iterations of
back-solves replace a factorisation.  It is refactorised when GMRES needs more
than ``max_krylov`` iterations, fails, or the matrix pattern changes.
"""
from __future__ import annotations

from typing import Optional

from petsc4py import PETSc

DIRECT = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}
REUSE = {"ksp_type": "gmres", "ksp_gmres_restart": 100, "ksp_rtol": 1e-12, "ksp_atol": 0.0,
         "ksp_max_it": 100, "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}


class LinearSolver:
    """Solves ``J x = b`` for a sequence of Jacobians, with PETSc options under ``prefix``."""

    def __init__(self, comm, prefix: str = "dolfinx_friction_", reuse: bool = False,
                 options: Optional[dict] = None, max_krylov: int = 30):
        opts = PETSc.Options()
        for key, value in {**(REUSE if reuse else DIRECT), **(options or {})}.items():
            if not opts.hasName(prefix + key):
                opts[prefix + key] = value
        self.ksp = PETSc.KSP().create(comm)
        self.ksp.setOptionsPrefix(prefix)
        self.ksp.setFromOptions()
        self.reuse, self.max_krylov = reuse, max_krylov
        self._factored: Optional[PETSc.Mat] = None
        self.factorisations = 0
        self.krylov_iterations = 0

    def solve(self, J: PETSc.Mat, b: PETSc.Vec, x: PETSc.Vec) -> bool:
        """Solve; returns False when the solver failed."""
        keep = self.reuse and J is self._factored
        if self._attempt(J, b, x, keep):
            return True
        return keep and self._attempt(J, b, x, False)

    def _attempt(self, J, b, x, keep: bool) -> bool:
        self.ksp.setOperators(J, J)
        self.ksp.getPC().setReusePreconditioner(keep)
        self.ksp.solve(b, x)
        if not keep:
            self.factorisations += 1
            self._factored = J
        its = self.ksp.getIterationNumber()
        self.krylov_iterations += its
        ok = self.ksp.getConvergedReason() > 0
        return ok and (not keep or its <= self.max_krylov)
