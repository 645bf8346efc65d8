"""Linear solves of the Newton iteration.

The default solver is MUMPS (unsymmetric LU) with the factorisation kept
(``reuse``): it preconditions GMRES for later Jacobians.  In small strain only the
contact part, supported on the contact surface, changes between iterations, so a few
Krylov iterations of back-solves replace a factorisation (1.6x faster at 67k dofs,
same Newton iterations: benchmarks/RESULTS.md).  It is refactorised when the matrix
pattern changes, when GMRES fails, and whenever keeping it does not pay: GMRES may take
as many iterations as fit into the time of the last factorisation (at most
``max_krylov``), and after a Krylov solve that took longer than a factorisation the next
:data:`PAUSE` Jacobians are factorised (small 2D problems factorise in milliseconds, and
a stiff contact change can need many Krylov iterations).  A fresh factorisation is a
plain direct solve.
``reuse=False`` factorises every Jacobian.  With user ``options`` (another solver) the
default is ``reuse=False``: their preconditioner is rebuilt for every Jacobian.
"""
from __future__ import annotations

import time
from typing import Optional

from mpi4py import MPI
from petsc4py import PETSc

DIRECT = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}
REUSE = {"ksp_type": "gmres", "ksp_gmres_restart": 30, "ksp_rtol": 1e-12, "ksp_atol": 0.0,
         "ksp_max_it": 30, "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}
#: Jacobians factorised afresh after a kept factorisation did not pay.
PAUSE = 3


class LinearSolver:
    """Solves ``J x = b`` for a sequence of Jacobians, with PETSc options under ``prefix``."""

    def __init__(self, comm, prefix: str = "dolfinx_friction_", reuse: Optional[bool] = None,
                 options: Optional[dict] = None, max_krylov: int = 30):
        if reuse is None:
            reuse = options is None
        opts = PETSc.Options()
        for key, value in {**(REUSE if reuse else DIRECT), **(options or {})}.items():
            if not opts.hasName(prefix + key):
                opts[prefix + key] = value
        self.ksp = PETSc.KSP().create(comm)
        self.ksp.setOptionsPrefix(prefix)
        self.ksp.setFromOptions()
        self.reuse, self.max_krylov = reuse, max_krylov
        self.comm = comm
        self._factored: Optional[PETSc.Mat] = None
        self._factor_time = 0.0  # seconds of the last solve with a fresh factorisation
        self._krylov_step = 0.0  # seconds per GMRES iteration with the kept factorisation
        self._paused = 0  # Jacobians still to factorise afresh
        self.factorisations = 0
        self.krylov_iterations = 0

    def solve(self, J: PETSc.Mat, b: PETSc.Vec, x: PETSc.Vec) -> bool:
        """Solve; returns False when the solver failed."""
        keep = self.reuse and J is self._factored and not self._paused
        self._paused = max(self._paused - 1, 0)
        ok, seconds = self._attempt(J, b, x, keep)
        if keep and (not ok or seconds > self._factor_time):
            self._paused = PAUSE
        if ok or not keep:
            return ok
        return self._attempt(J, b, x, False)[0]

    def _attempt(self, J, b, x, keep: bool) -> tuple[bool, float]:
        """One solve (with the kept factorisation or a fresh one): success, seconds."""
        start = time.perf_counter()
        if self.reuse:
            self.ksp.setType("gmres" if keep else "preonly")
            if keep:
                budget = self._factor_time / max(self._krylov_step, 1e-12)
                self.ksp.setTolerances(max_it=int(min(max(budget, 5), self.max_krylov)))
        self.ksp.setOperators(J, J)
        self.ksp.getPC().setReusePreconditioner(keep)
        self.ksp.solve(b, x)
        seconds = self.comm.allreduce(time.perf_counter() - start, op=MPI.MAX)
        its = self.ksp.getIterationNumber()
        if keep:
            self._krylov_step = seconds / max(its, 1)
        else:
            self.factorisations += 1
            self._factored, self._factor_time = J, seconds
        self.krylov_iterations += its
        return self.ksp.getConvergedReason() > 0, seconds
