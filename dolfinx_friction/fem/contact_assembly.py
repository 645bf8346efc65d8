"""The contact pair's element forces and tangents in the system numbering.

:class:`ContactAssembly` turns the evaluated elements of a
:class:`~dolfinx_friction.fem.pairing.ContactInteraction` into PETSc entries: the global dofs
of each candidate element (made once per search), the distinct couplings the candidates
may fill (the matrix pattern of the contact, found among node pairs) and each tangent
entry's slot among them, the Dirichlet rows and columns left out; on quadratic slave faces
against a rigid obstacle the blocks through which a slave node's force spreads over its
faces (:mod:`~dolfinx_friction.fem.slave_distribution`), with the mortar distribution the
blocks through which it reaches the master
(:mod:`~dolfinx_friction.fem.mortar_distribution`).  Every cache is kept while the
candidates (or the conditions) are the same objects.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from petsc4py import PETSc

from dolfinx_friction import _compat as compat
from dolfinx_friction.fem.numbering import DofLayout
from dolfinx_friction.fem.pairing import ContactInteraction

__all__ = ["ContactAssembly"]


class ContactAssembly:
    """Assembly of one contact pair's elements (``interaction``) into the system of the
    bodies' ``spaces`` numbered by ``layout`` (messages name the pair ``name``)."""

    def __init__(self, interaction: ContactInteraction, spaces: Sequence, layout: DofLayout,
                 name: str):
        self.interaction, self.spaces, self.layout, self.name = interaction, spaces, layout, name
        self.comm, self.gdim = interaction.comm, interaction.gdim
        self._bc_cache: tuple = ((), np.zeros(0, np.int64))
        self._dof_cache: tuple = (None,)  # (candidates, their dofs)
        # (candidates, rows, cols, slot, sorted node-pair keys, their width)
        self._slot_cache: tuple = (None,)

    def surface_dofs(self) -> np.ndarray:
        """Sorted global dofs of every node this rank's part of the contact can couple: its
        slave nodes and its master faces' nodes (a rigid obstacle's translation excluded).
        In serial, the couplings of every search lie within them."""
        inter = self.interaction
        nodes = [inter.slaves.nodes]
        if not inter.rigid:
            nodes.append(inter.master.nodes.ravel())
        nodes = np.unique(np.concatenate(nodes))
        return (nodes[:, None] * self.gdim + np.arange(self.gdim)).ravel()

    def _dofs(self) -> np.ndarray:
        """(n_candidates, nodes * gdim) global dofs of the candidate elements, -1 for the
        nodes of a rigid obstacle (no dofs); made once per search, read-only."""
        candidates = self.interaction.candidates
        if self._dof_cache[0] is not candidates:
            nodes, d = candidates.nodes, self.gdim
            dofs = (nodes[:, :, None] * d + np.arange(d)).reshape(len(nodes), nodes.shape[1] * d)
            dofs[np.repeat(nodes < 0, d, axis=1)] = -1
            dofs.flags.writeable = False
            self._dof_cache = (candidates, dofs)
        return self._dof_cache[1]

    def _coupling_slots(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The distinct couplings of the candidate elements (and of the stars their slave
        forces spread over, :meth:`_spread_blocks`), made once per search: their global
        ``rows`` and ``cols`` (m,), and ``slot`` (n_candidates, nd, nd), the index among
        them of each entry of each candidate's tangent (-1 where a rigid obstacle's node
        has no dofs).  Found among node pairs (gdim^2 fewer than dof pairs)."""
        candidates = self.interaction.candidates
        if self._slot_cache[0] is not candidates:
            nodes, d = candidates.nodes, self.gdim
            n, k = nodes.shape
            a = np.broadcast_to(nodes[:, :, None], (n, k, k))
            b = np.broadcast_to(nodes[:, None, :], (n, k, k))
            valid = (a >= 0) & (b >= 0)
            spread = [s.pattern(candidates.slave, nodes) for s in self._spreads()]
            star_rows = np.concatenate([np.zeros(0, np.int64)] + [r for r, _ in spread])
            star_cols = np.concatenate([np.zeros(0, np.int64)] + [c for _, c in spread])
            width = int(max(nodes.max(initial=0), star_rows.max(initial=0))) + 1
            keys = a[valid] * width + b[valid]
            pairs, inverse = np.unique(np.concatenate([keys, star_rows * width + star_cols]),
                                       return_inverse=True)
            pair = np.full((n, k, k), -1, dtype=np.int64)
            pair[valid] = inverse[: len(keys)]
            i = np.arange(d)
            # entry (node alpha, component i; node beta, component j) of a candidate's tangent
            slot = (pair[:, :, None, :, None] * d * d + i[:, None, None] * d + i).reshape(
                n, k * d, k * d)
            slot[np.repeat(np.repeat(pair < 0, d, axis=1), d, axis=2)] = -1
            rows = ((pairs // width)[:, None, None] * d + i[:, None]).repeat(d, axis=2)
            cols = ((pairs % width)[:, None, None] * d + i).repeat(d, axis=1)
            self._slot_cache = (candidates, rows.ravel(), cols.ravel(), slot, pairs, width)
        return self._slot_cache[1:4]

    def _node_dofs(self, nodes: np.ndarray, bcs: Sequence = ()) -> np.ndarray:
        """(n, m * gdim) global dofs of the nodes ``nodes`` (n, m), -1 for nodes < 0 and for
        the dofs of ``bcs``."""
        d = self.gdim
        dofs = (nodes[:, :, None] * d + np.arange(d)).reshape(len(nodes), nodes.shape[1] * d)
        dofs[np.repeat(nodes < 0, d, axis=1)] = -1
        fixed = self._bc_dofs(bcs) if len(bcs) else np.zeros(0, np.int64)
        if len(fixed):
            at = np.searchsorted(fixed, dofs).clip(max=len(fixed) - 1)
            dofs[fixed[at] == dofs] = -1
        return dofs

    def _spreads(self) -> list:
        """What replaces some of the elements' own rows: the stars of quadratic slave faces
        on a rigid obstacle (the slave node's row), the mortar distribution (the master
        face's rows)."""
        inter = self.interaction
        return [s for s in (inter.slaves.distribution, inter.mortar) if s is not None]

    def _own_part(self, el) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The elements' forces (n, nodes, d), tangents (n, nodes, d, nodes, d) and round-off
        (n, nodes * d) on their own nodes: without the slave node's rows where its force
        spreads over its star, without the master face's rows where the mortar weights
        hand it to the master (:meth:`_spread_blocks`; a slave node without weights keeps
        them)."""
        f, K, roundoff = el.result.f, el.result.K, el.roundoff
        inter, d = self.interaction, self.gdim
        if self._spreads():
            f, K, roundoff = f.copy(), K.copy(), roundoff.copy()
        if inter.slaves.distribution is not None:
            f[:, -1], K[:, -1], roundoff[:, -d:] = 0.0, 0.0, 0.0
        if inter.mortar is not None:
            mortar = inter.mortar.covered[el.slave]  # the others: nodal (no weights)
            f[mortar, :-1], K[mortar, :-1], roundoff[mortar, :-d] = 0.0, 0.0, 0.0
        return f, K, roundoff

    def _spread_blocks(self) -> list[tuple]:
        """The rows the slave nodes' forces spread over (:meth:`_spreads`): on quadratic slave
        faces against a rigid obstacle their stars
        (:class:`~dolfinx_friction.fem.slave_distribution.SlaveDistribution`), with the
        mortar distribution the master nodes
        (:class:`~dolfinx_friction.fem.mortar_distribution.MortarDistribution`); one block
        per element and spread: row nodes (n, r), column nodes (n, c), forces (n, r, d),
        tangents (n, r, d, c, d) and round-off (n, r, d; with |weight|)."""
        spreads = self._spreads()
        if not spreads:
            return []
        el = self._evaluated()
        n, k = el.nodes.shape
        blocks = []
        for spread in spreads:
            rows, f, K = spread.spread(el.slave, el.result.f[:, -1], el.result.K[:, -1])
            roundoff = (np.abs(spread.weights[el.slave])[:, :, None]
                        * el.roundoff.reshape(n, k, self.gdim)[:, None, -1])
            blocks.append((rows, el.nodes, f, K, roundoff))
        return blocks

    def _block_slots(self, rows: np.ndarray, cols: np.ndarray, bcs: Sequence) -> np.ndarray:
        """(n, r * d, c * d) indices among :meth:`couplings` of a block's entries (row nodes
        ``rows`` (n, r), column nodes ``cols`` (n, c)), -1 for absent nodes and for the rows
        and columns of ``bcs``."""
        self._coupling_slots()
        pairs, width = self._slot_cache[4:]
        d = self.gdim
        keys = rows[:, :, None] * width + cols[:, None, :]
        pair = np.searchsorted(pairs, keys).clip(max=max(len(pairs) - 1, 0))
        pair[(rows[:, :, None] < 0) | (cols[:, None, :] < 0)] = -1
        i = np.arange(d)
        slot = (pair[:, :, None, :, None] * d * d + i[:, None, None] * d + i).reshape(
            len(rows), rows.shape[1] * d, cols.shape[1] * d)
        slot[np.broadcast_to(pair[:, :, None, :, None] < 0, (*pair.shape[:2], d, pair.shape[2],
                                                               d)).reshape(slot.shape)] = -1
        masked = (self._node_dofs(rows, bcs)[:, :, None] < 0) | \
            (self._node_dofs(cols, bcs)[:, None, :] < 0)
        slot[masked] = -1
        return slot

    def _bc_dofs(self, bcs: Sequence) -> np.ndarray:
        """Sorted global dofs of the Dirichlet conditions ``bcs`` (all ranks; collective)."""
        key = tuple(id(bc) for bc in bcs)
        if self._bc_cache[0] == key:
            return self._bc_cache[1]
        d, own = self.gdim, []
        for bc in bcs:
            block = next((b for b, V in enumerate(self.spaces) if compat.bc_on_space(bc, V)),
                         None)
            if block is None:
                continue  # a condition on another space: none of the contact's rows
            local = compat.bc_local_dofs(bc, self.spaces[block].dofmap.index_map.size_local * d)
            own.append(self.layout.nodes(block)[local // d] * d + local % d)
        mine = np.concatenate(own) if own else np.zeros(0, np.int64)
        dofs = np.unique(np.concatenate(self.comm.allgather(mine)))
        self._bc_cache = (key, dofs)
        return dofs

    def _masked_dofs(self, bcs: Sequence) -> np.ndarray:
        """:meth:`_dofs` with -1 also for the dofs of ``bcs`` (read-only without them)."""
        dofs = self._dofs()
        fixed = self._bc_dofs(bcs)
        if len(fixed):
            at = np.searchsorted(fixed, dofs).clip(max=len(fixed) - 1)
            dofs = np.where(fixed[at] == dofs, -1, dofs)
        return dofs

    def add_residual(self, b: PETSc.Vec, bcs: Sequence = ()) -> None:
        """Add the contact forces (internal forces: residual = internal - external) into
        ``b`` (collective; ``b`` is assembled afterwards)."""
        el = self._evaluated()
        dofs = self._masked_dofs(bcs)[el.candidate]
        values = self._own_part(el)[0].reshape(len(dofs), dofs.shape[1])
        keep = dofs >= 0
        b.setValues(dofs[keep].astype(PETSc.IntType), values[keep], addv=PETSc.InsertMode.ADD)
        for rows, _, f, _, _ in self._spread_blocks():
            dofs = self._node_dofs(rows, bcs)
            keep = dofs >= 0
            b.setValues(dofs[keep].astype(PETSc.IntType), f.reshape(dofs.shape)[keep],
                        addv=PETSc.InsertMode.ADD)
        b.assemble()

    def add_jacobian(self, A: PETSc.Mat, bcs: Sequence = ()) -> None:
        """Add the contact tangent into ``A`` (collective; assembled afterwards).

        ``A`` holds the candidate couplings in its pattern (checked by
        :meth:`NodeToSurface.add_jacobian`).
        """
        el = self._evaluated()
        dofs = self._masked_dofs(bcs)[el.candidate].astype(PETSc.IntType)
        nd = dofs.shape[1]
        A.assemblyBegin(PETSc.Mat.AssemblyType.FLUSH)  # after dolfinx's INSERT of diagonals
        A.assemblyEnd(PETSc.Mat.AssemblyType.FLUSH)
        A.setValuesRCV(dofs, dofs, self._own_part(el)[1].reshape(-1, nd, nd),
                       addv=PETSc.InsertMode.ADD)
        for rows, cols, _, K, _ in self._spread_blocks():
            r = self._node_dofs(rows, bcs).astype(PETSc.IntType)
            c = self._node_dofs(cols, bcs).astype(PETSc.IntType)
            A.setValuesRCV(r, c, np.ascontiguousarray(K.reshape(len(r), r.shape[1], c.shape[1])),
                           addv=PETSc.InsertMode.ADD)
        A.assemble()

    def add_roundoff(self, s: PETSc.Vec) -> None:
        """Add the size of the round-off of the contact forces (their sensitivity to the
        coordinates, which carry the clearance) into ``s``, per dof (not assembled)."""
        el = self._evaluated()
        dofs = self._dofs()[el.candidate]
        keep = dofs >= 0
        s.setValues(dofs[keep].astype(PETSc.IntType), self._own_part(el)[2][keep],
                    addv=PETSc.InsertMode.ADD)
        for rows, _, _, _, roundoff in self._spread_blocks():
            dofs = self._node_dofs(rows)
            keep = dofs >= 0
            s.setValues(dofs[keep].astype(PETSc.IntType), roundoff.reshape(dofs.shape)[keep],
                        addv=PETSc.InsertMode.ADD)

    def couplings(self) -> tuple[np.ndarray, np.ndarray]:
        """Global ``(rows, cols)`` of every entry the contact tangent may fill until the
        next search (each candidate element's dofs, all against all), each once."""
        rows, cols, _ = self._coupling_slots()
        return rows, cols

    def coupling_values(self, bcs: Sequence = ()) -> np.ndarray:
        """Tangent values in the order of :meth:`couplings`: the sum of the elements'
        entries (0 where no element couples, and in the rows and columns of ``bcs``)."""
        el = self._evaluated()
        rows, _, slot = self._coupling_slots()
        slot = slot[el.candidate]
        K = self._own_part(el)[1].reshape(slot.shape)
        masked = self._masked_dofs(bcs)[el.candidate] < 0
        keep = (slot >= 0) & ~(masked[:, :, None] | masked[:, None, :])
        values = np.bincount(slot[keep], weights=K[keep], minlength=len(rows))
        for r, c, _, K, _ in self._spread_blocks():
            slot = self._block_slots(r, c, bcs)
            keep = slot >= 0
            values += np.bincount(slot[keep], weights=K.reshape(slot.shape)[keep],
                                  minlength=len(rows))
        return values

    def element_entries(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Global ``(rows, cols, values)`` of the current elements' tangents only (what
        :meth:`coupling_values` holds where it is not zero by construction; a rigid
        obstacle's rows and columns left out; no bcs)."""
        el = self._evaluated()
        blocks = [(el.nodes, el.nodes, self._own_part(el)[1])]
        blocks += [(r, c, K) for r, c, _, K, _ in self._spread_blocks()]
        out = []
        for r, c, K in blocks:
            r, c = self._node_dofs(r), self._node_dofs(c)
            K = K.reshape(len(r), r.shape[1], c.shape[1])
            keep = (r >= 0)[:, :, None] & (c >= 0)[:, None, :]
            out.append((np.broadcast_to(r[:, :, None], K.shape)[keep],
                        np.broadcast_to(c[:, None, :], K.shape)[keep], K[keep]))
        return tuple(np.concatenate(parts) for parts in zip(*out))

    def _evaluated(self):
        el = self.interaction.elements
        if el.result is None:
            raise RuntimeError(f"{self.name}: call update(x) before assembling")
        return el
