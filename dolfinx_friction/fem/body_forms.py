"""One body of a block problem: its compiled residual and Jacobian forms, vector and matrix."""
from __future__ import annotations

import ctypes
import functools
from typing import Optional, Sequence

import numpy as np
import ufl
from petsc4py import PETSc

from dolfinx_friction import _compat as compat

__all__ = ["BodyForms", "is_linear"]


#: :func:`is_linear`'s answers by the Jacobian's signature and ``u``'s place among its
#: coefficients (the signature numbers them in that order): expanding the derivative of a
#: Neo-Hookean Jacobian takes ~40 ms, a tenth of a 1k-dof run (the form's compilation
#: computes the signature anyway)
_LINEAR: dict = {}


def is_linear(jacobian: ufl.Form, u) -> bool:
    """Whether a Jacobian form does not depend on ``u`` (its body is linear)."""
    from ufl.algorithms import expand_derivatives
    coefficients = jacobian.coefficients()
    if u not in coefficients:
        return True
    key = (jacobian.signature(), coefficients.index(u))
    if key not in _LINEAR:
        _LINEAR[key] = not expand_derivatives(ufl.derivative(jacobian, u)).integrals()
    return _LINEAR[key]


@functools.cache
def _petsc() -> ctypes.CDLL:
    """The PETSc library petsc4py links to (its symbols are found through petsc4py's)."""
    return ctypes.CDLL(PETSc.__file__)


def _baij_values(A: PETSc.Mat, nnz: int) -> np.ndarray:
    """A copy of the array (nnz,) a serial block-AIJ matrix of reals stores its values in:
    block by block in the order of the block rows' sorted block columns, each block by
    columns."""
    mat, array = ctypes.c_void_p(A.handle), ctypes.POINTER(ctypes.c_double)()
    if _petsc().MatSeqBAIJGetArray(mat, ctypes.byref(array)):
        raise RuntimeError("MatSeqBAIJGetArray failed")
    values = np.ctypeslib.as_array(array, (nnz,)).copy()
    _petsc().MatSeqBAIJRestoreArray(mat, ctypes.byref(array))
    return values


class BodyForms:
    """One block: compiled residual and Jacobian forms, its own vector and matrix (block
    AIJ for a body that is not linear: dolfinx inserts its dense nodal blocks in 0.6x the
    time of AIJ's; in serial its values are copied from PETSc's own array, in its order,
    an eighth of the time of ``getValuesCSR``'s walk row by row)."""

    def __init__(self, F: ufl.Form, u, J: Optional[ufl.Form], bcs: Sequence):
        V = u.function_space
        J = J if J is not None else ufl.derivative(F, u)
        self.u, self.V, self.bcs = u, V, list(bcs)
        self.linear = is_linear(J, u)
        #: linear and zero at u = 0: its residual is the product of its Jacobian with u
        self.homogeneous = self.linear and not ufl.replace(
            F, {u: ufl.zero(*u.ufl_shape)}).integrals()
        self.F, self.J = compat.form(F), compat.form(J)
        self.b = compat.create_vector(self.F)
        self.A = compat.create_matrix(self.J, blocked=not self.linear)
        self.n_owned = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
        self._stored = 0  # the length of PETSc's array of A if jacobian_values reads it

    def residual(self) -> np.ndarray:
        """Owned values of ``F(u)`` (ghost contributions summed)."""
        with self.b.localForm() as local:
            local.set(0.0)
        compat.assemble_vector_into(self.b, self.F)
        return self.b.getArray(readonly=True)[: self.n_owned]

    def assemble_jacobian(self) -> None:
        """The body's Jacobian at its current ``u`` into :attr:`A` (no bcs)."""
        self.A.zeroEntries()
        compat.assemble_matrix_into(self.A, self.J)

    def jacobian_entries(self) -> tuple[np.ndarray, np.ndarray]:
        """Local (rows, cols) (nnz,) of the entries of :attr:`A` (assembled) in the order of
        :meth:`jacobian_values`: PETSc's storage order for a serial block-AIJ matrix (checked
        here against ``getValuesCSR``), else CSR order."""
        indptr, cols, data = self.A.getValuesCSR()
        rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
        cols = cols.astype(np.int64)
        self._stored = 0
        if self.A.getType() == PETSc.Mat.Type.SEQBAIJ and PETSc.ScalarType == np.float64:
            # the CSR entry at position q of row r is entry (r % bs, q % bs) of the row's
            # block q // bs: stored at its block row's start + bs q + r % bs
            bs = self.A.getBlockSize()
            within = rows % bs
            stored = indptr[rows - within] + bs * (np.arange(len(data)) - indptr[rows]) + within
            if np.array_equal(_baij_values(self.A, len(data))[stored], data):
                self._stored = len(data)
                rows[stored], cols[stored] = rows.copy(), cols.copy()
        return rows, cols

    def jacobian_values(self) -> np.ndarray:
        """Values (nnz,) of :attr:`A` as last assembled, in the order of
        :meth:`jacobian_entries` (a copy)."""
        if self._stored:
            return _baij_values(self.A, self._stored)
        return self.A.getValuesCSR()[2]
