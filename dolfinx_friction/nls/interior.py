"""A Newton step with the interior of the linear bodies condensed out (serial).

Where a linear body (a stiff die, a foundation) meets a finite-strain one, the rows and
columns of the Jacobian at the linear body's free dofs off every contact surface (the
interior ``I``) are its constant stiffness ``K``; only the other free rows ``P`` (the
nonlinear bodies, the linear bodies' contact surfaces ``S``, the obstacles) change.  With
``K_II`` factorised once for the run, the step solves

    (J_PP - D) x_P = b_P - K_PI K_II^-1 b_I,    D = K_SI K_II^-1 K_IS  (dense, S x S),
    x_I = K_II^-1 (b_I - K_IS x_S),

so each iteration factorises ``J_PP - D`` instead of the whole free system: on the
one-layer ironing the die's interior is 56 % of the free dofs of the test mesh.  ``D``
costs one back-solve per dof of ``S`` at the start; the path is taken while ``D`` has no
more entries than a :data:`SHARE` of the Jacobian's.  ``Z = K_II^-1 K_IS`` (dense, I x S),
made on the way to ``D``, is kept where it has no more entries than ``K_II``'s
factorisation (no more memory): then ``x_I = y_I - Z x_S`` with ``y_I = K_II^-1 b_I``, one
back-solve of ``K_II`` per step instead of two (the product is 4-16x faster than a
back-solve reading as many factor entries: 0.006 against 0.098 ms on the press + shear
block of benchmarks/bench_ccx_nlgeom.py, 0.078 against 0.334 ms at 350k entries).
``K_II`` is factorised by PETSc's own LU (nested dissection) up to
:data:`~dolfinx_friction.nls.defaults.KEPT_NATIVE_MAX_DOFS` rows, else by MUMPS
(:func:`~dolfinx_friction.nls.defaults.factorisation` with ``kept``): its back-solves, one
per step, then carry no fixed cost of MUMPS's (0.017 against 0.095 ms on the 432 rows of
the press + shear block).  Options under the solver's prefix plus ``interior_`` (e.g.
``interior_pc_factor_mat_solver_type``) choose otherwise.
"""
from __future__ import annotations

from typing import Callable, Optional

import numpy as np
from petsc4py import PETSc

from dolfinx_friction.fem.pattern import csr_values
from dolfinx_friction.nls.defaults import factorisation

__all__ = ["Interior", "factor_entries"]

#: ``D`` (|S|^2 entries) may take at most this share of the Jacobian's non-zeros.
SHARE = 0.25
#: Columns of ``K_II^-1 K_IS`` computed per back-solve call (dense right-hand sides).
COLUMNS = 64


def _csr_block(indptr: np.ndarray, cols: np.ndarray, rows: np.ndarray, position: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(row, col, slot) of the CSR entries in ``rows`` whose column has a ``position`` >= 0:
    the rows' and columns' positions in the block and the entries' slots in the CSR."""
    counts = indptr[rows + 1] - indptr[rows]
    slots = np.repeat(indptr[rows] - np.cumsum(counts) + counts, counts) + np.arange(
        counts.sum())
    row = np.repeat(np.arange(len(rows)), counts)
    col = position[cols[slots]]
    keep = col >= 0
    return row[keep], col[keep], slots[keep]


def factor_entries(F: PETSc.Mat) -> float:
    """Entries of a factorisation (at least 1): MUMPS's ``INFOG(20)``, else the factor's."""
    if F.getType() != "mumps":
        return max(F.getInfo()["nz_used"], 1.0)
    entries = F.getMumpsInfog(20)  # negative: millions
    return max(entries if entries >= 0 else -entries * 1e6, 1.0)


def _factorised(ksp: PETSc.KSP) -> bool:
    """Whether ``ksp`` (a factorisation) factorised its operator: a solve that did not fail
    (MUMPS's negative ``INFOG(1)``, PETSc's zero pivot or missing diagonal)."""
    b, x = ksp.getOperators()[0].createVecs()
    try:
        b.set(1.0)
        ksp.solve(b, x)
        return ksp.getConvergedReason() > 0 and bool(np.isfinite(x.norm()))
    except PETSc.Error:
        return False
    finally:
        b.destroy()
        x.destroy()


class Interior:
    """Solves ``J x = b`` with the constant rows ``I`` condensed out (serial, square ``J``
    whose constrained rows are identity rows with zero right-hand side)."""

    def __init__(self, prefix: str):
        self._prefix = prefix
        self._key: Optional[tuple] = None  # (constrained, interior) the set-up is for
        #: the path is taken for the rows of the last :meth:`set_up`
        self.usable = False
        self._ksp: Optional[PETSc.KSP] = None
        self._pattern: Optional[tuple] = None  # (J, its non-zeros) the matrix was made for
        self._B: Optional[PETSc.Mat] = None
        self.K_SI: Optional[PETSc.Mat] = None
        self.K_IS: Optional[PETSc.Mat] = None
        self.Z: Optional[np.ndarray] = None  # K_II^-1 K_IS (|I|, |S|), where kept
        #: the package that factorised ``K_II`` ("" before a set-up that took the path)
        self.package = ""

    def set_up(self, J: PETSc.Mat, constrained: np.ndarray, interior: np.ndarray) -> bool:
        """Factorise ``K_II``, compute ``D`` (when the rows changed); whether the path is
        taken (:meth:`solve` solves the condensed system ``J_PP - D``)."""
        key = self._key
        if key is None or not (np.array_equal(key[0], constrained)
                               and np.array_equal(key[1], interior)):
            self._make(J, constrained, interior)
        return self.usable

    def _make(self, J: PETSc.Mat, constrained: np.ndarray, interior: np.ndarray) -> None:
        """:meth:`set_up` for new rows."""
        self._key, self._pattern = (constrained.copy(), interior.copy()), None
        n = J.getSize()[0]
        indptr, cols, _ = J.getValuesCSR()
        role = np.zeros(n, np.int8)  # 0: P, 1: I, 2: constrained
        role[interior], role[constrained] = 1, 2
        self.P, self.I = np.flatnonzero(role == 0), np.flatnonzero(role == 1)
        in_I, in_P = np.full(n, -1), np.full(n, -1)
        in_I[self.I], in_P[self.P] = np.arange(len(self.I)), np.arange(len(self.P))
        coupled_rows = _csr_block(indptr, cols, self.P, in_I)[0]  # K_PI's rows
        coupled_cols = _csr_block(indptr, cols, self.I, in_P)[1]  # K_IP's columns
        self.S = np.union1d(coupled_rows, coupled_cols)  # positions in P coupled to I
        self.usable = (len(self.I) > 0 and len(self.S) ** 2 <= SHARE * len(cols))
        if not self.usable:
            return
        comm = PETSc.COMM_SELF
        for old in (self.K_SI, self.K_IS):
            if old is not None:
                old.destroy()
        rows = PETSc.IS().createGeneral(self.I.astype(PETSc.IntType), comm=comm)
        srows = PETSc.IS().createGeneral(self.P[self.S].astype(PETSc.IntType), comm=comm)
        K_II = J.createSubMatrix(rows, rows)
        self.K_SI = J.createSubMatrix(srows, rows)
        self.K_IS = J.createSubMatrix(rows, srows)
        rows.destroy()
        srows.destroy()
        if self._ksp is not None:
            self._ksp.destroy()
        gdim = J.getBlockSize() if J.getBlockSize() in (2, 3) else 3  # (the Jacobian's: gdim)
        chosen = factorisation(len(self.I), gdim, 1, kept=True)
        # PETSc's LU does not pivot: MUMPS factorises what it could not
        for package in dict.fromkeys((chosen, "mumps")):
            self._ksp = self._factorise(K_II, package)
            if self._ksp is not None:
                break
        if self._ksp is None:  # K_II singular: a part of a linear body held by I only
            self.usable = False
            K_II.destroy()
            return
        F = self._ksp.getPC().getFactorMatrix()
        self.package = self._ksp.getPC().getFactorSolverType()
        ptr, col, val = self.K_IS.getValuesCSR()
        row = np.repeat(np.arange(len(self.I)), np.diff(ptr))
        D = np.zeros((len(self.S), len(self.S)))
        keep_Z = len(self.I) * len(self.S) <= factor_entries(F)
        self.Z = np.empty((len(self.I), len(self.S))) if keep_Z else None
        for start in range(0, len(self.S), COLUMNS):
            chunk = slice(start, start + COLUMNS)
            width = len(self.S[chunk])
            K_chunk = np.zeros((len(self.I), width), order="F")  # K_IS's columns in chunk
            at = (col >= start) & (col < start + width)
            K_chunk[row[at], col[at] - start] = val[at]
            B = PETSc.Mat().createDense(K_chunk.shape, array=K_chunk, comm=comm)
            X = PETSc.Mat().createDense(K_chunk.shape, comm=comm)
            X.setUp()
            F.matSolve(B, X)
            if keep_Z:
                self.Z[:, chunk] = X.getDenseArray()
            KZ = self.K_SI.matMult(X)  # K_SI K_II^-1 K_IS, these columns
            D[:, chunk] = KZ.getDenseArray()
            for mat in (B, X, KZ):
                mat.destroy()
        K_II.destroy()
        self.D = D
        self._yI, self._rS = self.K_SI.createVecs()  # sizes |I|, |S|
        self._xS, self._rI = self.K_IS.createVecs()  # sizes |S|, |I|

    def _factorise(self, K: PETSc.Mat, package: str) -> Optional[PETSc.KSP]:
        """A ``preonly`` LU of ``K`` by ``package`` (the options under the prefix plus
        ``interior_`` win); None where it failed."""
        ksp = PETSc.KSP().create(PETSc.COMM_SELF)
        ksp.setOptionsPrefix(self._prefix + "interior_")
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType("lu")
        pc.setFactorSolverType(package)
        if package == "petsc":
            pc.setFactorOrdering("nd")
        ksp.setFromOptions()
        ksp.setOperators(K, K)
        if _factorised(ksp):
            return ksp
        ksp.destroy()
        return None

    def destroy(self) -> None:
        """Destroy its factorisation, matrices and vectors; the next solve sets up afresh."""
        for name in ("_ksp", "_B", "K_SI", "K_IS", "_yI", "_rS", "_xS", "_rI"):
            obj = getattr(self, name, None)
            if obj is not None:
                obj.destroy()

    def _matrix(self, J: PETSc.Mat) -> PETSc.Mat:
        """``J_PP - D``, its pattern made once per pattern of ``J``."""
        key = (J, J.getInfo()["nz_allocated"])
        if self._pattern is None or self._pattern[0] is not J or self._pattern[1] != key[1]:
            indptr, cols, _ = J.getValuesCSR()
            position = np.full(J.getSize()[0], -1)
            position[self.P] = np.arange(len(self.P))
            r, c, slots = _csr_block(indptr, cols, self.P, position)
            S = self.S
            m = len(self.P)
            # both key lists are sorted (CSR order): D's keys missing from J's are merged in
            J_keys, D_keys = r * m + c, (S[:, None] * m + S[None, :]).ravel()
            at = np.searchsorted(J_keys, D_keys)
            new = np.ones(len(D_keys), bool)
            inside = at < len(J_keys)
            new[inside] = J_keys[at[inside]] != D_keys[inside]
            keys = np.insert(J_keys, at[new], D_keys[new])
            # J's key i moves up by the number of D's keys inserted before it
            to = np.arange(len(J_keys)) + np.cumsum(
                np.bincount(at[new], minlength=len(J_keys) + 1))[:len(J_keys)]
            ptr = np.searchsorted(keys, np.arange(m + 1) * m).astype(PETSc.IntType)
            csr = (ptr, (keys % m).astype(PETSc.IntType), np.zeros(len(keys)))
            if self._B is not None:
                self._B.destroy()
            self._B = PETSc.Mat().createAIJWithArrays((m, m), csr, comm=PETSc.COMM_SELF)
            self._csr, self._values = csr, csr[2]
            # each slot of B takes J's value (D's alone: any, then overwritten with -D), and
            # -D is added where it meets J's and is not zero
            self._sources = np.zeros(len(keys), np.int64)
            self._sources[to] = slots
            at, minus_D = np.searchsorted(keys, D_keys), -self.D.ravel()
            met = ~new & (minus_D != 0.0)
            self._minus_D = (at[new], minus_D[new]), (at[met], minus_D[met])
            self._pattern = key
        (alone, minus_alone), (met, minus_met) = self._minus_D
        np.take(csr_values(J), self._sources, out=self._values)
        self._values[alone] = minus_alone
        self._values[met] += minus_met
        self._B.assemble()  # the values changed (a factorisation is redone)
        return self._B

    def solve(self, solve: Callable, J: PETSc.Mat, b: PETSc.Vec, x: PETSc.Vec,
              again: bool = False) -> bool:
        """``solve(A, b, x)`` on the condensed system, then ``x`` in every row; after a
        :meth:`set_up` for ``J``'s rows that took the path.  ``again``: with the condensed
        matrix of the last call as it was (not refilled from ``J``)."""
        B = self._B if again else self._matrix(J)
        bv = b.getArray(readonly=True)
        self._rI.setArray(bv[self.I])
        self._ksp.solve(self._rI, self._yI)  # y_I = K_II^-1 b_I
        self.K_SI.mult(self._yI, self._rS)
        rhs, x_P = B.createVecs()
        values = bv[self.P].copy()
        values[self.S] -= self._rS.getArray(readonly=True)
        rhs.setArray(values)
        ok = solve(B, rhs, x_P)
        xv = np.zeros(len(bv))
        xv[self.P] = x_P.getArray(readonly=True)
        if self.Z is not None:  # x_I = y_I - Z x_S
            xv[self.I] = self._yI.getArray(readonly=True) - self.Z @ xv[self.P[self.S]]
        else:
            self._xS.setArray(xv[self.P[self.S]])
            self.K_IS.mult(self._xS, self._rI)
            self._rI.setArray(bv[self.I] - self._rI.getArray(readonly=True))
            self._ksp.solve(self._rI, self._yI)  # x_I = K_II^-1 (b_I - K_IS x_S)
            xv[self.I] = self._yI.getArray(readonly=True)
        rhs.destroy()
        x_P.destroy()
        x.setArray(xv)
        return ok
