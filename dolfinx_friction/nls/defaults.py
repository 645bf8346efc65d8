"""Newton's settings that the scene model shares with the solvers (no PETSc here: the
scene model reads them without importing the solvers)."""
from __future__ import annotations

__all__ = ["CONVERGENCE", "STALL_ITERATIONS"]

#: Newton's convergence tests (:mod:`dolfinx_friction.nls.newton`)
CONVERGENCE = ("residual", "reactions")
#: Newton gives up on an increment (it is cut back) after this many iterations without a
#: new lowest residual (counted from the first step's): contact statuses cycling at the
#: edge of a growing zone converge faster in halved increments (benchmarks/RESULTS.md;
#: in converging solves off that kind the longest such run is 2)
STALL_ITERATIONS = 6
