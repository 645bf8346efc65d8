"""A Newton step on the rows no constraint holds.

The Jacobian of a :class:`~dolfinx_friction.BlockProblem` has identity rows where a
Dirichlet condition (or a prescribed obstacle) holds a dof, and the residual is zero there:
the step is zero in those rows, and the other rows' equations do not involve their columns.
A factorisation of the whole matrix still carries them: MUMPS orders the symmetrised
pattern, in which a held dof couples to its neighbours like a free one.  Solving on the
free rows only leaves them out: on the one-layer hexahedral ironing (u_z held on every
node, a third of the dofs) the factorisation takes a quarter of the flops and half of the
time (benchmarks/RESULTS.md, "CalculiX NLGEOM").
"""
from __future__ import annotations

from typing import Optional

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

__all__ = ["FreeRows"]


class FreeRows:
    """The restriction of ``J x = b`` to the rows outside ``constrained`` (local indices of
    owned rows, identity rows of ``J`` with zero right-hand side), kept between solves: the
    index set while the constrained rows are the same, the submatrix (refilled) while ``J``
    is the same matrix with the same pattern."""

    def __init__(self) -> None:
        self._constrained: Optional[np.ndarray] = None
        self._rows: Optional[PETSc.IS] = None
        self._reduces = False
        self._key: Optional[tuple] = None  # (J, its non-zeros) the submatrix was made from
        self._sub: Optional[PETSc.Mat] = None
        self._x: Optional[PETSc.Vec] = None

    def _index_set(self, J: PETSc.Mat, constrained: np.ndarray) -> None:
        """The free rows as a parallel index set; collective: every rank makes it anew
        when the rows changed on any rank."""
        same = self._constrained is not None and np.array_equal(constrained, self._constrained)
        if J.getComm().tompi4py().allreduce(same, op=MPI.LAND):
            return
        self._constrained = constrained.copy()
        start, end = J.getOwnershipRange()
        free = np.setdiff1d(np.arange(end - start), constrained) + start
        if self._rows is not None:
            self._rows.destroy()
        self._rows = PETSc.IS().createGeneral(free.astype(PETSc.IntType), comm=J.getComm())
        self._reduces = J.getComm().tompi4py().allreduce(len(constrained)) > 0
        self._forget()

    def _forget(self) -> None:
        for obj in (self._sub, self._x):
            if obj is not None:
                obj.destroy()
        self._key = self._sub = self._x = None

    def matrix(self, J: PETSc.Mat, constrained: np.ndarray) -> PETSc.Mat:
        """``J`` on the free rows and columns (``J`` itself where no row is constrained);
        collective."""
        self._index_set(J, constrained)
        if not self._reduces:
            return J
        key = (J, J.getInfo(PETSc.Mat.InfoType.GLOBAL_SUM)["nz_allocated"])
        if self._key is not None and key[0] is self._key[0] and key[1] == self._key[1]:
            self._sub = J.createSubMatrix(self._rows, self._rows, submat=self._sub)
        else:
            self._forget()
            self._sub = J.createSubMatrix(self._rows, self._rows)
            self._x = self._sub.createVecRight()
            self._key = key
        return self._sub

    def solve(self, solve, J: PETSc.Mat, b: PETSc.Vec, x: PETSc.Vec,
              constrained: np.ndarray, again: bool = False) -> bool:
        """``solve(A, b, x)`` on the free rows (``x`` zero in the constrained ones);
        returns what it returned.  ``again``: with the submatrix of the last call as it
        was (not refilled from ``J``)."""
        if again:
            A = self._sub if self._reduces else J
        else:
            A = self.matrix(J, constrained)
        if A is J:
            return solve(J, b, x)
        b_free = b.getSubVector(self._rows)
        try:
            ok = solve(A, b_free, self._x)
        finally:
            b.restoreSubVector(self._rows, b_free)
        x.zeroEntries()
        x_free = x.getSubVector(self._rows)
        self._x.copy(x_free)
        x.restoreSubVector(self._rows, x_free)
        return ok

    def destroy(self) -> None:
        """Destroy its index set and submatrix (collective); the next solve makes them."""
        self._forget()
        if self._rows is not None:
            self._rows.destroy()
        self._rows = self._constrained = None
