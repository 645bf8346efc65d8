"""Distributed sparse matrices assembled from coordinate (COO) triplets.

Every rank contributes entries ``(row, col, value)`` by global index, for rows
it owns or not (contact elements add into master rows owned elsewhere).  The
pattern, the union of all entries plus every owned diagonal, is built once:
remote entries are sent to the owners of their rows, and each owner keeps, for
every incoming value, its slot in the compressed row storage.  Refilling the
matrix then costs one message exchange and a ``bincount``: no new non-zeros,
no search per entry.
"""
from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc


#: the attribute of a serial matrix that holds the array PETSc stores its values in
_VALUES = "dolfinx_friction_values"
#: the attribute of a matrix filled by :meth:`CooPattern.fill_over`: (base, slots, the
#: matrix's state after that fill)
_BASE = "dolfinx_friction_base"


def ownership_ends(comm: MPI.Comm, n_owned: int) -> np.ndarray:
    """Exclusive end of every rank's contiguous ownership range."""
    return np.cumsum(comm.allgather(n_owned)).astype(np.int64)


def _row_pointers(rows: np.ndarray, n_rows: int) -> np.ndarray:
    """CSR row pointers (n_rows + 1,) of entries in the given local rows (in CSR order)."""
    return np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=n_rows))]).astype(
        PETSc.IntType)


def held_values(A: PETSc.Mat) -> np.ndarray | None:
    """The array (nnz,) PETSc stores a matrix's CSR values in where
    :meth:`CooPattern.create_matrix` made it in serial (writing it changes the matrix:
    assemble after), else None."""
    return A.getAttr(_VALUES)


def csr_values(A: PETSc.Mat) -> np.ndarray:
    """The CSR values of a serial matrix: :func:`held_values` where it has them (no copy;
    not to be written), else a copy."""
    values = held_values(A)
    return A.getValuesCSR()[2] if values is None else values


class _Block:
    """One group of COO entries: how its values travel to their rows' owners."""

    def __init__(self, comm: MPI.Comm, ends: np.ndarray, rows: np.ndarray):
        owner = np.searchsorted(ends, rows, side="right")
        self.order = np.argsort(owner, kind="stable")
        self.send_counts = np.bincount(owner, minlength=comm.size).astype(np.int64)
        self.recv_counts = np.array(comm.alltoall(self.send_counts.tolist()), dtype=np.int64)
        self.slots = np.empty(0, dtype=np.int64)
        self.unique: np.ndarray | None = None  # its distinct slots (sorted), and of each entry
        self.position: np.ndarray | None = None  # its index in them
        self.distinct: bool | None = None  # serial, and no two entries share a slot

    def exchange(self, comm: MPI.Comm, send: np.ndarray, dtype) -> np.ndarray:
        """Send entries (in constructor order) to the owners of their rows."""
        recv = np.empty(int(self.recv_counts.sum()), dtype=dtype)
        mpi_type = MPI.INT64_T if dtype == np.int64 else MPI.DOUBLE
        comm.Alltoallv([np.ascontiguousarray(send[self.order], dtype=dtype), self.send_counts,
                        mpi_type], [recv, self.recv_counts, mpi_type])
        return recv


class CooPattern:
    """The pattern of a square distributed matrix built from blocks of COO entries.

    ``blocks`` is a list of ``(rows, cols)`` global index arrays, e.g. the bulk
    stiffness and the contact elements; :meth:`gather_values` turns the values
    of one block into CSR data, so a constant block is summed only once.
    :meth:`extended` adds blocks to a pattern without sorting its entries again.
    """

    def __init__(self, comm: MPI.Comm, n_owned: int, blocks: list[tuple[np.ndarray, np.ndarray]]):
        self.comm = comm
        ends = ownership_ends(comm, n_owned)
        self.n_owned, self.n_global = n_owned, int(ends[-1])
        self.start = int(ends[comm.rank] - n_owned)
        self._ends = ends
        self._blocks, keys = self._receive(blocks)
        diag = np.arange(self.start, self.start + n_owned, dtype=np.int64)
        keys.append((diag - self.start) * self.n_global + diag)
        unique, inverse = np.unique(np.concatenate(keys), return_inverse=True)
        bounds = np.cumsum([0] + [len(k) for k in keys])
        for k, block in enumerate(self._blocks):
            block.slots = inverse[bounds[k]:bounds[k + 1]]
        self.diagonal_slots = inverse[bounds[-2]:]
        self._set_keys(unique)

    def _receive(self, blocks) -> tuple[list[_Block], list[np.ndarray]]:
        """Send each block's entries to their rows' owners; the blocks and the received keys
        ``local row * n_global + col``."""
        out, keys = [], []
        for rows, cols in blocks:
            rows = np.asarray(rows, dtype=np.int64).ravel()
            block = _Block(self.comm, self._ends, rows)
            mine_rows = block.exchange(self.comm, rows, np.int64)
            mine_cols = block.exchange(self.comm, np.asarray(cols, dtype=np.int64).ravel(),
                                       np.int64)
            keys.append((mine_rows - self.start) * self.n_global + mine_cols)
            out.append(block)
        return out, keys

    def _set_keys(self, unique: np.ndarray) -> None:
        """The compressed rows of the sorted unique keys."""
        self._keys = unique
        self.nnz = len(unique)
        self._row_of_slot = unique // self.n_global
        self.indptr = _row_pointers(self._row_of_slot, self.n_owned)
        self.indices = (unique % self.n_global).astype(PETSc.IntType)

    def extended(self, blocks: list[tuple[np.ndarray, np.ndarray]]) -> "CooPattern":
        """This pattern plus the entries of more blocks (collective).

        The result's blocks are the new ones only; its ``base_slots`` (this pattern's
        nnz,) are the slots of this pattern's entries in the result.  Costs a few passes over this pattern's entries
        instead of sorting them again (the bulk stiffness, when the contact couplings
        change).
        """
        new = object.__new__(CooPattern)
        new.comm, new.n_owned, new.n_global = self.comm, self.n_owned, self.n_global
        new.start, new._ends = self.start, self._ends
        new._blocks, keys = new._receive(blocks)
        extra, inverse = np.unique(np.concatenate(keys + [np.zeros(0, np.int64)]),
                                   return_inverse=True)
        base = self._keys
        at = np.searchsorted(base, extra)
        known = at < len(base)
        known[known] = base[at[known]] == extra[known]
        added, where = extra[~known], at[~known]
        # base slot i moves up by the number of added keys that sort before it
        new.base_slots = np.arange(len(base)) + np.cumsum(
            np.bincount(where, minlength=len(base) + 1))[:len(base)]
        slot_of_extra = np.empty(len(extra), dtype=np.int64)
        slot_of_extra[known] = new.base_slots[at[known]]
        slot_of_extra[~known] = where + np.arange(len(added))
        bounds = np.cumsum([0] + [len(k) for k in keys])
        for k, block in enumerate(new._blocks):
            block.slots = slot_of_extra[inverse[bounds[k]:bounds[k + 1]]]
        new.diagonal_slots = new.base_slots[self.diagonal_slots]
        # this pattern's compressed rows with the added keys inserted (no division of
        # every key again)
        new._keys, new.nnz = np.insert(base, where, added), len(base) + len(added)
        rows = added // self.n_global
        new._row_of_slot = np.insert(self._row_of_slot, where, rows)
        new.indices = np.insert(self.indices, where,
                                (added % self.n_global).astype(PETSc.IntType))
        new.indptr = self.indptr + _row_pointers(rows, self.n_owned)
        return new

    def gather_values(self, block: int, values: np.ndarray) -> np.ndarray:
        """CSR data holding the sum of one block's values (given in its constructor order)."""
        b = self._blocks[block]
        received = b.exchange(self.comm, np.asarray(values, dtype=float).ravel(), np.float64)
        return np.bincount(b.slots, weights=received, minlength=self.nnz)

    def distinct_slots(self, block: int) -> np.ndarray | None:
        """The slots (the block's size,) of one block's entries in its constructor order,
        where writing its values there gives :meth:`gather_values`: in serial, if no two
        of its entries share a slot; else None."""
        b = self._blocks[block]
        if b.distinct is None:
            b.distinct = self.comm.size == 1 and len(np.unique(b.slots)) == len(b.slots)
        return b.slots if b.distinct else None

    def put_values(self, block: int, values: np.ndarray, out: np.ndarray) -> None:
        """Add one block's values (given in its constructor order) into CSR data ``out``
        that is zero wherever the block has entries: written at its
        :meth:`distinct_slots` where it has them (no exchange, no sum), else
        :meth:`gather_values` is added."""
        slots = self.distinct_slots(block)
        if slots is not None:
            out[slots] = values
        else:
            out += self.gather_values(block, values)

    def gather_slots(self, block: int, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One block's values summed into its own slots: ``(slots, sums)``, ``slots`` sorted
        and unique (what :meth:`gather_values` gives there; zero elsewhere)."""
        b = self._blocks[block]
        if b.unique is None:
            b.unique, b.position = np.unique(b.slots, return_inverse=True)
        received = b.exchange(self.comm, np.asarray(values, dtype=float).ravel(), np.float64)
        return b.unique, np.bincount(b.position, weights=received, minlength=len(b.unique))

    def row_slots(self, local_rows: np.ndarray, columns: np.ndarray | None = None
                  ) -> np.ndarray:
        """Slots (sorted) of all entries in the given owned rows (local indices) and, if
        given, in the given columns (global indices)."""
        mask = np.zeros(self.n_owned, dtype=bool)
        mask[local_rows] = True
        found = mask[self._row_of_slot]
        if columns is not None:
            mask = np.zeros(self.n_global, dtype=bool)
            mask[columns] = True
            found |= mask[self.indices]
        return np.flatnonzero(found)

    def create_matrix(self, block_size: int = 1) -> PETSc.Mat:
        """A matrix of this pattern, zero.  In serial PETSc stores its values in an array
        of ours (:meth:`fill` writes them in place); under MPI it copies them."""
        size = self._sizes()
        if self.comm.size == 1:
            csr = (self.indptr, self.indices, np.zeros(self.nnz, dtype=PETSc.ScalarType))
            A = PETSc.Mat().createAIJWithArrays(size, csr, comm=self.comm)
            A.setBlockSize(block_size)
            A.setAttr(_VALUES, csr[2])
        else:
            A = PETSc.Mat().createAIJ(size, bsize=block_size, csr=(self.indptr, self.indices),
                                      comm=self.comm)
        A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
        return A

    def _sizes(self) -> tuple:
        """PETSc's (local, global) sizes of rows and columns of this pattern's matrices."""
        return (self.n_owned, self.n_global), (self.n_owned, self.n_global)

    def blocks_matrix(self, blocks: list[int], data: np.ndarray) -> PETSc.Mat:
        """An assembled matrix of only the given blocks' entries, valued from CSR ``data``
        of this pattern (a product with it skips the other blocks' slots: the linear
        bodies' ``K u`` beside a nonlinear body; collective)."""
        slots = np.unique(np.concatenate([self._blocks[k].slots for k in blocks]
                                         + [np.zeros(0, np.int64)]))
        csr = (_row_pointers(self._row_of_slot[slots], self.n_owned), self.indices[slots],
               np.asarray(data[slots], dtype=PETSc.ScalarType))
        A = PETSc.Mat().createAIJ(self._sizes(), csr=csr, comm=self.comm)
        A.assemble()
        return A

    def fill(self, A: PETSc.Mat, data: np.ndarray) -> None:
        """Overwrite all values of ``A`` (created by :meth:`create_matrix`) with CSR ``data``."""
        values = held_values(A)
        if values is None:
            A.setValuesCSR(self.indptr, self.indices, data)
        else:
            values[:] = data
        A.assemble()  # also tells PETSc the values changed (a factorisation is redone)

    def fill_over(self, A: PETSc.Mat, base: np.ndarray, slots: np.ndarray,
                  values: np.ndarray) -> None:
        """Overwrite the values of ``A`` with CSR ``base``, except ``values`` at ``slots``
        (sorted).  Where ``A`` is unchanged since its last such fill with the same ``base``
        and ``slots`` objects, only ``slots`` are written: in place in serial, by
        ``MatSetValues`` into this rank's rows under MPI (no copy of the local matrix)."""
        last = A.getAttr(_BASE)
        kept = (last is not None and last[0] is base and last[1] is slots
                and last[2] == A.stateGet())
        held = held_values(A)
        if held is not None:
            if not kept:
                held[:] = base
            held[slots] = values
        elif kept:
            rows, counts = np.unique(self._row_of_slot[slots], return_counts=True)
            A.setValuesIJV(np.concatenate([[0], np.cumsum(counts)]).astype(PETSc.IntType),
                           self.indices[slots], np.asarray(values, dtype=PETSc.ScalarType),
                           rowmap=(rows + self.start).astype(PETSc.IntType))
        else:
            data = base.copy()
            data[slots] = values
            A.setValuesCSR(self.indptr, self.indices, data)
        A.assemble()  # also tells PETSc the values changed (a factorisation is redone)
        A.setAttr(_BASE, (base, slots, A.stateGet()))

    def fill_layered(self, A: PETSc.Mat, base: np.ndarray,
                     writes: list[tuple[np.ndarray, np.ndarray]], slots: np.ndarray,
                     added: np.ndarray) -> None:
        """Fill a serial ``A`` with :func:`held_values` in one pass over its own array: CSR
        ``base``, overwritten by each ``(at, values)`` of ``writes`` (slots of this
        pattern), ``added`` added at ``slots`` (a nonlinear body's values over the
        linear bodies', the contacts' tangents on top)."""
        held = held_values(A)
        held[:] = base
        for at, values in writes:
            held[at] = values
        held[slots] += added
        A.assemble()  # also tells PETSc the values changed (a factorisation is redone)
