"""Newton's and the linear solver's settings that the scene model shares with the solvers
(no PETSc here: the scene model reads them without importing the solvers)."""
from __future__ import annotations

from typing import Optional

__all__ = ["CHORD", "CONVERGENCE", "DIRECT_MAX_DOFS", "ITERATIVE", "KEPT_NATIVE_MAX_DOFS",
           "LINEAR_KINDS", "NATIVE_MAX_DOFS", "STALL_ITERATIONS", "choose", "factorisation",
           "unsafe_option"]

#: Newton's convergence tests (:mod:`dolfinx_friction.nls.newton`)
CONVERGENCE = ("residual", "reactions")
#: Newton gives up on an increment (it is cut back) after this many iterations without a
#: new lowest residual (counted from the first step's): contact statuses cycling at the
#: edge of a growing zone converge faster in halved increments (benchmarks/RESULTS.md;
#: in converging solves off that kind the longest such run is 2)
STALL_ITERATIONS = 6

#: a Newton step of a finite-strain problem solves with the last factorisation (a chord
#: step) where the last whole step, with no contact change, cut the residual to this
#: share or less (:meth:`~dolfinx_friction.nls.newton.Newton._chord_step`; 0: never)
CHORD = 0.1

#: the kinds of linear solver a run may ask for (a scene's ``[solver] linear``)
LINEAR_KINDS = ("auto", "direct", "iterative")
#: GMRES preconditioned by smoothed-aggregation algebraic multigrid (the Jacobian carries
#: its block size and the bodies' rigid-body modes as near null space); it stops at the
#: relative residual Newton asks (:func:`~dolfinx_friction.nls.newton.forcing`)
ITERATIVE = {"ksp_type": "gmres", "ksp_gmres_restart": 200, "ksp_max_it": 1000,
             "ksp_atol": 0.0, "pc_type": "gamg"}
#: the largest system ``"auto"`` factorises, by geometric dimension.  A 3D LU factor grows
#: as dofs^(4/3): on the frictional block of benchmarks/RESULTS.md ("Cost per Newton
#: iteration") at 114k dofs MUMPS with its kept factorisation took 7.6 s per Newton
#: iteration and 5.9 GB, GMRES + GAMG 7.6 s and 1.9 GB; at 193k MUMPS 32 s, GAMG 31 s at
#: 432k.  2D factors stay cheap far longer.
DIRECT_MAX_DOFS = {2: 1_000_000, 3: 120_000}


def choose(kind: str, dofs: int, gdim: int, direct_max_dofs: Optional[int] = None) -> str:
    """``"direct"`` or ``"iterative"`` for a system of ``dofs`` unknowns in ``gdim``
    dimensions: ``kind`` itself, or for ``"auto"`` direct up to ``direct_max_dofs``
    (default :data:`DIRECT_MAX_DOFS`)."""
    if kind != "auto":
        return kind
    limit = DIRECT_MAX_DOFS[gdim] if direct_max_dofs is None else direct_max_dofs
    return "direct" if dofs <= limit else "iterative"


#: the largest system, by geometric dimension, that a serial factorisation leaves to PETSc's
#: own LU (Cholesky where symmetric; nested-dissection ordering) rather than MUMPS: MUMPS
#: spends a fixed ~0.2 ms per factorisation (0.18 against 0.01 ms at 84 2D dofs), while
#: PETSc's unblocked elimination loses to MUMPS's dense fronts as they grow, the sooner in
#: 3D (benchmarks/RESULTS.md, "Direct solvers of small systems": numeric factorisation and
#: solve of an elastic stiffness, unsymmetric / symmetric (Cholesky against LDL^T), 2D:
#: 3.1 / 2.3 ms against 3.7 / 2.7 at 2,664 dofs, 11.4 / 7.9 against 9.4 / 7.1 at 5,940;
#: 3D: 0.55 against 0.84 ms at 300 dofs, 2.3 against 1.8 at 540)
NATIVE_MAX_DOFS = {2: 3_000, 3: 400}
#: the same for a matrix factorised once and back-solved at every Newton step of a run
#: (the linear bodies' interior of :mod:`~dolfinx_friction.nls.interior`): MUMPS's
#: back-solve carries a fixed cost PETSc's lacks (0.078 against 0.010 ms at 300 3D dofs,
#: 0.43 against 0.07 at 2,664 2D dofs), and PETSc's dearer first factorisation has paid
#: for itself within 50 back-solves up to 12,960 2D and 882 3D dofs (after 123 at 1,944
#: 3D dofs, 498 at 3,630: benchmarks/RESULTS.md, "Direct solvers of small systems")
KEPT_NATIVE_MAX_DOFS = {2: 13_000, 3: 900}


def factorisation(dofs: int, gdim: int, ranks: int, kept: bool = False) -> str:
    """The package that factorises a system of ``dofs`` unknowns in ``gdim`` dimensions on
    ``ranks`` ranks: ``"petsc"`` (serial, up to :data:`NATIVE_MAX_DOFS`; ``kept``: a matrix
    factorised once for many back-solves, up to :data:`KEPT_NATIVE_MAX_DOFS`) or
    ``"mumps"``."""
    limit = (KEPT_NATIVE_MAX_DOFS if kept else NATIVE_MAX_DOFS)[gdim]
    return "petsc" if ranks == 1 and dofs <= limit else "mumps"


def unsafe_option(name: str, value: object) -> str:
    """Why a PETSc option from an input file may not be set ("" if it may): an input file
    never runs code (``python`` types load Python classes) nor writes files of its own
    choosing (``*_view`` options with a file)."""
    if "python" in name or str(value).strip().lower() == "python":
        return "would load Python code"
    if "view" in name and ":" in str(value):
        return "would write a file"
    return ""
