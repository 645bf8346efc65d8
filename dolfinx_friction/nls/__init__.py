"""Nonlinear solution: Newton with line search and the round-off floor (or PETSc SNES),
load stepping with cutbacks and rollback, and the linear solvers (MUMPS with a kept
factorisation, the condensed path) with their PETSc options."""
from dolfinx_friction._lazy import lazy_names

_PUBLIC = {
    "Newton": "newton", "NewtonTrace": "newton", "snes_solve": "newton", "SNESNewton": "newton",
    "solve_steps": "stepping", "IncrementRecord": "stepping", "ConvergenceError": "stepping",
    "LinearSolver": "linear", "Condensed": "linear",
}
__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
