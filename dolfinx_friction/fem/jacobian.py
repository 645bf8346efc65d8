"""The Jacobian of a :class:`~dolfinx_friction.fem.block_problem.BlockProblem`: the matrix
and the caches that make filling it again cheap.

The bodies' Jacobians are joined in one COO pattern (:class:`~dolfinx_friction.fem.pattern.
CooPattern`) in the block numbering; each new pattern of the contact couplings
(``couplings_version``) extends it to a new matrix, which carries the block size and the
bodies' rigid-body modes as near null space (for algebraic multigrid).  Filling the matrix
at an iterate writes the static values (the linear bodies' stiffness, assembled once, with
the constrained rows, and for a symmetric solve columns, made identity), the nonlinear
bodies' values (assembled at the iterate) at their slots but in the constrained rows, and
adds the contacts' tangents: in serial in one pass over the matrix's own array; with only
linear bodies, only the contacts' slots while the matrix holds the static values of the
last fill.  Every cache is kept while the very objects it was made from (pattern, values,
constrained rows) are the same.
:meth:`BlockJacobian.split` gives the Jacobian as a constant bulk matrix plus the contact
entries instead (:class:`JacobianSplit`, for the condensed solve).
"""
from __future__ import annotations

import weakref
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Optional

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx_friction.fem.pattern import CooPattern, held_values

if TYPE_CHECKING:
    from dolfinx_friction.fem.block_problem import BlockProblem

__all__ = ["BlockJacobian", "JacobianSplit"]


@dataclass
class JacobianSplit:
    """The Jacobian ``J = K + C``: ``bulk`` is ``K``, the bodies' constant stiffness with
    the constrained rows made identity rows (a distributed PETSc matrix, the same object
    while it does not change); ``C``, the contact tangent (zero in constrained rows), is the
    sum over the ranks of their ``values`` at global ``(rows, cols)`` (this rank's elements'
    entries; repeated pairs add), all within the contact surfaces' global ``dofs`` (sorted,
    of every rank: the same on all).  With ``symmetric`` (``K`` is), the constrained
    columns are zero in both: ``J`` is ``jacobian(x, symmetric=True)``.  ``fixed``: the
    constrained global dofs (sorted, of every rank)."""

    bulk: PETSc.Mat
    dofs: np.ndarray
    rows: np.ndarray
    cols: np.ndarray
    values: np.ndarray
    symmetric: bool = False
    fixed: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))


def _same(kept: tuple, key: tuple) -> bool:
    """Whether a cache's key holds the very objects of ``key`` (identity, not equality)."""
    return all(a is b for a, b in zip(kept, key))


class BlockJacobian:
    """The Jacobian matrix of ``problem`` and its caches (collective where it assembles).

    On construction the bodies' Jacobians are assembled at their current displacement (a
    linear body's values are kept for the run) and :attr:`base`, their pattern, is made;
    :attr:`K_linear` is the stiffness of the bodies whose residual is ``K u`` (None if
    there are none).
    """

    def __init__(self, problem: BlockProblem, homogeneous: list[int]):
        # the problem owns this object: a strong reference back would make a cycle, and
        # the problem's matrices would wait for the collector's rare full pass
        self.problem = weakref.proxy(problem)
        self.base, values = self._bulk_pattern()
        #: each linear body's values in :attr:`base`
        self.linear_data = {k: self.base.gather_values(k, values[k])
                            for k, body in enumerate(problem.bodies) if body.linear}
        self._linear_sum = sum(self.linear_data.values(), np.zeros(self.base.nnz))
        self.K_linear: Optional[PETSc.Mat] = None
        if homogeneous:
            self.K_linear = self.base.blocks_matrix(
                homogeneous, sum(self.linear_data[k] for k in homogeneous))
        self._pattern: Optional[CooPattern] = None
        self._versions: Optional[list[int]] = None
        self._J: Optional[PETSc.Mat] = None
        self._abs: Optional[PETSc.Mat] = None  # |J_bulk|, for the round-off floor
        self._assemblies = 0  # of the nonlinear bodies' Jacobians since the construction
        self._abs_assembly = 0  # the one |J_bulk| holds
        self._bulk_data: Optional[np.ndarray] = None  # bulk values, all bodies linear
        self._zeroed: Optional[tuple] = None  # (key, slots of the constrained rows, columns)
        self._sources: Optional[tuple] = None  # (key, where the static values come from)
        self._static: Optional[tuple] = None  # (key, free obstacle rows, Jacobian without contact)
        self._targets: Optional[tuple] = None  # (key, where the nonlinear bodies' values go)
        self._coupling_slots: Optional[tuple] = None  # (key, slots, zeroed, contacts' positions)
        self._bulk_bc: Optional[tuple] = None  # (constrained rows, bulk matrix with them)
        self._surface_dofs: Optional[np.ndarray] = None  # of all contacts and ranks (fixed)
        self._constrained: Optional[tuple] = None  # (constrained rows, their global dofs)
        self._modes: Optional[PETSc.NullSpace] = None
        self._spring = 0.0

    def _bulk_pattern(self) -> tuple[CooPattern, list[np.ndarray]]:
        """The pattern of the bodies' Jacobians in the block numbering, and each body's
        CSR values at its current ``u`` (assembled once for both)."""
        p = self.problem
        d = p.gdim
        blocks, values = [], []
        for k, body in enumerate(p.bodies):
            body.assemble_jacobian()  # (the body's forms may come from an earlier problem)
            rows, cols = body.jacobian_entries()
            values.append(body.jacobian_values())
            blocks.append((p.layout.nodes(k)[rows // d] * d + rows % d,
                           p.layout.from_block_global(k, cols // d) * d + cols % d))
        return CooPattern(p.comm, p.layout.n_owned * d, blocks), values

    def scale_of_bulk(self, x: PETSc.Vec, scale: PETSc.Vec) -> None:
        """``|J_bulk| |x| + |f_ext|`` into the round-off scale (contacts add theirs); a
        nonlinear body's ``J`` is the one of the last :meth:`jacobian` (before the first,
        at its current ``u``)."""
        if self._abs is None or self._abs_assembly != self._assemblies:
            if not self._assemblies:
                self._assemble_nonlinear()
            if self._abs is None:
                self._abs = self.base.create_matrix()
            self.base.fill(self._abs, np.abs(self.bulk_values()))
            self._abs_assembly = self._assemblies
        ax = x.copy()
        ax.abs()
        self._abs.mult(ax, scale)
        ax.destroy()
        scale.setArray(scale.getArray() + np.abs(self.problem.f_ext))

    def _assemble_nonlinear(self) -> None:
        """The nonlinear bodies' Jacobians at their current ``u``."""
        for body in self.problem.bodies:
            if not body.linear:
                body.assemble_jacobian()
        self._assemblies += 1

    def bulk_values(self) -> np.ndarray:
        """Values (bulk nnz,) of the bodies' Jacobians in the bulk pattern, a nonlinear
        body's as last assembled."""
        base = self._linear_sum.copy()  # zero in the other bodies' rows
        for k, body in enumerate(self.problem.bodies):
            if not body.linear:
                self.base.put_values(k, body.jacobian_values(), base)
        return base

    def matrix(self) -> PETSc.Mat:
        """The Jacobian matrix for the current contact couplings (a new one when they
        changed since the last call; collective).  It carries the block size and the
        bodies' rigid-body modes as near null space (for algebraic multigrid)."""
        p = self.problem
        versions = [c.couplings_version for c in p.contacts]
        if self._J is None or versions != self._versions:
            self._pattern = self.base.extended([c.couplings() for c in p.contacts])
            if self._J is not None:
                self._J.destroy()
            self._J = self._pattern.create_matrix(p.gdim)
            self._J.setNearNullSpace(self.rigid_body_modes())
            for c in p.contacts:
                c.register_matrix(self._J)
            self._versions = versions
        return self._J

    def jacobian(self, x: PETSc.Vec, A: Optional[PETSc.Mat] = None,
                 symmetric: bool = False) -> PETSc.Mat:
        """Fill the Jacobian at ``x`` (the contacts at their last update) into ``A``
        (default :meth:`matrix`); returns it.  ``symmetric``: the constrained columns are
        zeroed too (symmetric where :attr:`symmetric`); a Newton step is the same, since the
        residual is zero in the constrained rows."""
        p = self.problem
        with p.timers.measure("bulk_assembly"):
            A = self.matrix() if A is None else A
            if p.linear:
                if self._bulk_data is None:
                    self._bulk_data = self.bulk_values()
                base, targets = self._bulk_data, None
            else:
                p.scatter(x)
                self._assemble_nonlinear()
                targets = (self._nonlinear_targets(symmetric)
                           if held_values(A) is not None else None)
                base = self.bulk_values() if targets is None else self._linear_sum
        with p.timers.measure("contact_assembly"):
            static = self._static_values(base, symmetric)
            if targets is None:
                slots, contact = self._contact_values(symmetric)
                self._pattern.fill_over(A, static, slots, static[slots] + contact)
                return A
            slots, contact = self._contact_entries(symmetric)
            self._pattern.fill_layered(
                A, static, [(at, p.bodies[k].jacobian_values()[kept]) for k, kept, at in targets],
                slots, contact)
        return A

    def _nonlinear_targets(self, symmetric: bool) -> Optional[list[tuple]]:
        """For each nonlinear body ``k``, ``(k, kept, slots)``: the positions in its
        ``jacobian_values`` of the entries outside :meth:`_zeroed_slots` and their slots
        in :meth:`matrix`'s pattern; None where a body's values must be summed (under
        MPI).  Kept with the pattern and the constrained rows."""
        p = self.problem
        rows = p.constrained_rows
        key = (self._pattern, rows, symmetric)
        cached = self._targets
        if cached is None or not _same(cached[0], key):
            nonlinear = [k for k, body in enumerate(p.bodies) if not body.linear]
            own = [self.base.distinct_slots(k) for k in nonlinear]
            targets = None
            if all(slots is not None for slots in own):
                zeroed = np.zeros(self._pattern.nnz, bool)
                zeroed[self._zeroed_slots(rows, symmetric)] = True
                targets = []
                for k, slots in zip(nonlinear, own):
                    at = self._pattern.base_slots[slots]
                    kept = np.flatnonzero(~zeroed[at])
                    targets.append((k, kept, at[kept]))
            self._targets = cached = (key, targets)
        return cached[1]

    def _static_values(self, base: np.ndarray, symmetric: bool) -> np.ndarray:
        """CSR data (pattern of :meth:`matrix`) of the Jacobian without contact: the bulk
        ``base`` (in one pass: the linear bodies' only), the constrained rows
        (``symmetric``: and columns) zero but for a unit diagonal, the obstacles' springs.
        Kept while pattern, ``base`` and rows are the same objects and the free obstacle
        rows the same (with a one-pass fill or only linear bodies: once per search)."""
        p = self.problem
        rows, free = p.constrained_rows, p.free_obstacle_rows()
        key = (self._pattern, base, rows, symmetric)
        cached = self._static
        if cached is not None and _same(cached[0], key) and np.array_equal(cached[1], free):
            return cached[2]
        data = np.take(np.concatenate([base, [0.0, 1.0]]), self._static_sources(rows, symmetric))
        # A force-controlled obstacle may have no stiffness along some axis (a
        # frictionless plane in its own plane): a tiny spring in the Jacobian only keeps
        # it regular; the residual, hence the solution, is unchanged.
        data[self._pattern.diagonal_slots[free]] += self._rigid_spring()
        self._static = (key, free, data)
        return data

    def _static_sources(self, rows: np.ndarray, symmetric: bool) -> np.ndarray:
        """For each slot of :meth:`matrix`'s pattern, where :meth:`_static_values` takes its
        value: a slot of the bulk pattern, or past its end a zero (a slot the bulk pattern
        does not have, the constrained rows, ``symmetric``: and columns) or a one (their
        diagonal); kept with the pattern and the rows (one gather per Jacobian)."""
        key = (self._pattern, rows, symmetric)
        cached = self._sources
        if cached is None or not _same(cached[0], key):
            nnz = self.base.nnz
            sources = np.full(self._pattern.nnz, nnz)
            sources[self._pattern.base_slots] = np.arange(nnz)
            sources[self._zeroed_slots(rows, symmetric)] = nnz
            sources[self._pattern.diagonal_slots[rows]] = nnz + 1
            self._sources = cached = (key, sources)
        return cached[1]

    def _zeroed_slots(self, rows: np.ndarray, symmetric: bool) -> np.ndarray:
        """CSR slots of the constrained ``rows`` (``symmetric``: and of their columns on
        every rank; collective), kept with the pattern and the rows."""
        key = (self._pattern, rows, symmetric)
        cached = self._zeroed
        if cached is None or not _same(cached[0], key):
            columns = self.constrained_dofs() if symmetric else None
            self._zeroed = cached = (key, self._pattern.row_slots(rows, columns))
        return cached[1]

    def _contact_values(self, symmetric: bool) -> tuple[np.ndarray, np.ndarray]:
        """The slots (sorted) of the contacts' couplings (kept with the pattern) and the
        contacts' tangents there, zero in the constrained rows (``symmetric``: and
        columns)."""
        p = self.problem
        rows = p.constrained_rows
        gathered = [self._pattern.gather_slots(k, c.coupling_values())
                    for k, c in enumerate(p.contacts)]
        key = (self._pattern, rows, symmetric)
        cached = self._coupling_slots
        if cached is None or not _same(cached[0], key):
            slots = np.unique(np.concatenate([at for at, _ in gathered]
                                             + [np.zeros(0, np.int64)]))
            zeroed = np.isin(slots, self._zeroed_slots(rows, symmetric))
            positions = [np.searchsorted(slots, at) for at, _ in gathered]
            self._coupling_slots = cached = (key, slots, zeroed, positions)
        _, slots, zeroed, positions = cached
        contact = np.zeros(len(slots))
        for at, (_, sums) in zip(positions, gathered):
            contact[at] += sums
        contact[zeroed] = 0.0
        return slots, contact

    def _contact_entries(self, symmetric: bool) -> tuple[np.ndarray, np.ndarray]:
        """The contacts' tangents where they are not zero, summed: ``(slots, values)``,
        ``slots`` distinct, zero in the constrained rows (``symmetric``: and columns).  Serial
        (each coupling has a slot of its own, :meth:`CooPattern.distinct_slots`): no pass
        over every candidate's couplings, only the evaluated elements' entries (22 of a
        search's 3,388 candidate faces on the full ironing); else :meth:`_contact_values`."""
        p = self.problem
        own = [self._pattern.distinct_slots(k) for k in range(len(p.contacts))]
        if any(at is None for at in own):
            return self._contact_values(symmetric)
        parts = []
        for at, c in zip(own, p.contacts):
            index, values = c.coupling_entries()
            parts.append((at[index], values))
        slots = np.concatenate([at for at, _ in parts] + [np.zeros(0, np.int64)])
        values = np.concatenate([v for _, v in parts] + [np.zeros(0)])
        if len(parts) > 1:  # two pairs may couple the same dofs
            slots, inverse = np.unique(slots, return_inverse=True)
            values = np.bincount(inverse, weights=values, minlength=len(slots))
        zeroed = self._zeroed_slots(p.constrained_rows, symmetric)
        at = np.searchsorted(zeroed, slots).clip(max=max(len(zeroed) - 1, 0))
        if len(zeroed):
            values[zeroed[at] == slots] = 0.0
        return slots, values

    def constrained_dofs(self) -> np.ndarray:
        """Sorted global dofs of the constrained rows of every rank (collective; kept while
        the rows are the same object)."""
        rows = self.problem.constrained_rows
        if self._constrained is None or self._constrained[0] is not rows:
            mine = self.global_rows(rows)
            self._constrained = (rows, np.unique(np.concatenate(
                self.problem.comm.allgather(mine))).astype(mine.dtype))
        return self._constrained[1]

    def global_rows(self, rows: np.ndarray) -> np.ndarray:
        """Global indices of owned local rows."""
        return (rows + self.problem.x.getOwnershipRange()[0]).astype(PETSc.IntType)

    def split(self) -> Optional["JacobianSplit"]:
        """The Jacobian at the contacts' last update as a constant bulk matrix plus a
        contact part supported on the contact surfaces (no matrix is filled), or None where
        that split does not hold or is not implemented: a body that is not linear, rigid
        obstacles (their rows have no bulk stiffness).  Collective."""
        p = self.problem
        if not p.linear or p.n_obstacles or not p.contacts:
            return None
        rows = p.constrained_rows
        with p.timers.measure("bulk_assembly"):
            if self._bulk_bc is None or self._bulk_bc[0] is not rows:
                if self._bulk_bc is not None:
                    self._bulk_bc[1].destroy()
                data = self.bulk_values()
                data[self.base.row_slots(rows)] = 0.0
                data[self.base.diagonal_slots[rows]] = 1.0
                K = self.base.create_matrix(p.gdim)
                self.base.fill(K, data)
                if p.bodies_symmetric():
                    K.zeroRowsColumns(self.global_rows(rows), diag=1.0)
                self._bulk_bc = (rows, K)
        with p.timers.measure("contact_assembly"):
            fixed = self.constrained_dofs()
            entries = [c.element_entries() for c in p.contacts]
            r, k, v = (np.concatenate(e) for e in zip(*entries))
            keep = (v != 0.0) & ~np.isin(r, fixed)
            if p.bodies_symmetric():  # the constrained columns eliminated, as in K
                keep &= ~np.isin(k, fixed)
            if self._surface_dofs is None:
                mine = np.concatenate([c.surface_dofs() for c in p.contacts])
                self._surface_dofs = np.unique(np.concatenate(p.comm.allgather(mine)))
        return JacobianSplit(self._bulk_bc[1], self._surface_dofs, r[keep], k[keep], v[keep],
                             p.bodies_symmetric(), fixed)

    def _rigid_spring(self) -> float:
        """1e-12 of the largest bulk diagonal entry (found once)."""
        p = self.problem
        if not self._spring and p.n_obstacles:
            diagonal = np.abs(self.bulk_values()[self.base.diagonal_slots])
            self._spring = 1e-12 * p.comm.allreduce(float(diagonal.max(initial=0.0)),
                                                       op=MPI.MAX)
        return self._spring

    def rigid_body_modes(self) -> PETSc.NullSpace:
        """Translations and rotations of every body, orthonormal (collective): the near null
        space of elasticity for algebraic multigrid.  An obstacle only translates."""
        p = self.problem
        if self._modes is not None:
            return self._modes
        d = p.gdim
        modes = [p.x.duplicate() for _ in range(3 if d == 2 else 6)]
        values = np.zeros((len(modes), p.x.getLocalSize() // d, d))
        for k, V in enumerate(p.spaces):
            nodes = slice(int(p.layout.block_offsets[k]), int(p.layout.block_offsets[k + 1]))
            X = V.tabulate_dof_coordinates()[: V.dofmap.index_map.size_local, :d]
            values[:d, nodes] = np.eye(d)[:, None, :]
            for j, (a, c) in enumerate([(0, 1)] if d == 2 else [(0, 1), (1, 2), (2, 0)]):
                values[d + j, nodes, a], values[d + j, nodes, c] = -X[:, c], X[:, a]
        for k in range(p.n_obstacles):
            values[:d, p.obstacle_rows(k)[:1] // d] = np.eye(d)[:, None, :]
        for k, mode in enumerate(modes):  # modified Gram-Schmidt
            mode.setArray(values[k].ravel())
            for previous in modes[:k]:
                mode.axpy(-mode.dot(previous), previous)
            mode.scale(1.0 / mode.norm())
        self._modes = PETSc.NullSpace().create(vectors=modes, comm=p.comm)
        return self._modes
