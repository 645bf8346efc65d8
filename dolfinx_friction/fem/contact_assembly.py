"""The contact pair's element forces and tangents in the system numbering.

:class:`ContactAssembly` turns the evaluated elements of a
:class:`~dolfinx_friction.fem.pairing.ContactInteraction` into PETSc entries: the global dofs
of each candidate element (made once per search), the couplings the matrix pattern holds
(found among node pairs: those of a wider search than the candidates', kept while every
later search's candidates fill only them, :meth:`ContactAssembly.renew`) and each tangent
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

#: node-pair key ``row * _WIDTH + col`` (system node numbers below 2^31)
_WIDTH = 1 << 31


def _node_rows(n: int, owner: np.ndarray, node: np.ndarray) -> np.ndarray:
    """(n, width) the distinct nodes ``node`` (m,) >= 0 of each of ``n`` owners (``owner``
    (m,)), -1 beyond each row's end."""
    keep = node >= 0
    keys = np.unique(owner[keep] * _WIDTH + node[keep])
    row, value = keys // _WIDTH, keys % _WIDTH
    rank = np.arange(len(keys)) - np.searchsorted(row, np.arange(n))[row]
    out = np.full((n, int(rank.max(initial=-1)) + 1), -1, dtype=np.int64)
    out[row, rank] = value
    return out


class ContactAssembly:
    """Assembly of one contact pair's elements (``interaction``) into the system of the
    bodies' ``spaces`` numbered by ``layout`` (messages name the pair ``name``)."""

    def __init__(self, interaction: ContactInteraction, spaces: Sequence, layout: DofLayout,
                 name: str):
        self.interaction, self.spaces, self.layout, self.name = interaction, spaces, layout, name
        self.comm, self.gdim = interaction.comm, interaction.gdim
        #: (the conditions, their sorted global dofs): the conditions themselves are held,
        #: so that a new condition never meets the dofs of a freed one of the same id
        self._bc_cache: tuple = ((), np.zeros(0, np.int64))
        self._dof_cache: tuple = (None,)  # (candidates, their dofs)
        #: the couplings of the matrix pattern: sorted node-pair keys, global rows, cols
        self._held: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

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

    def _keys(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """(n, r, c) node-pair keys of row nodes ``rows`` (n, r) against column nodes
        ``cols`` (n, c), -1 where either is absent (-1)."""
        keys = rows[:, :, None] * _WIDTH + cols[:, None, :]
        keys[(rows[:, :, None] < 0) | (cols[:, None, :] < 0)] = -1
        return keys

    def _filled_keys(self) -> np.ndarray:
        """Node-pair keys the tangent may fill until the next search: each candidate's
        nodes all against all, and the rows its slave force spreads over against them."""
        c = self.interaction.candidates
        keys = [self._keys(c.nodes, c.nodes).ravel()]
        keys += [self._keys(s.nodes[c.slave], c.nodes).ravel() for s in self.spreads()]
        keys = np.concatenate(keys)
        return keys[keys >= 0]

    def holds(self) -> bool:
        """Whether the couplings of the matrix pattern (:meth:`renew`) hold every entry the
        current candidates and spreads may fill (this rank)."""
        if self._held is None:
            return False
        pairs, keys = self._held[0], self._filled_keys()
        if not len(pairs):
            return not len(keys)
        return bool(np.all(pairs[np.searchsorted(pairs, keys).clip(max=len(pairs) - 1)]
                           == keys))

    def renew(self) -> None:
        """Make the couplings of a new matrix pattern: the first, those of the current
        candidates and spreads; every later one (the contact moved out of a pattern) also
        those of the neighbourhood (:attr:`~dolfinx_friction.fem.pairing.
        ContactInteraction.neighbourhood`) and, with the mortar distribution, every master
        node of a slave node's candidate faces (and of its weights) as rows against the
        neighbourhood's nodes, so that the candidates and the weights of the next
        increments of a slide may move within them."""
        inter, d = self.interaction, self.gdim
        near = inter.neighbourhood
        keys = [self._filled_keys()]
        if self._held is not None:
            keys.append(self._keys(near.nodes, near.nodes).ravel())
        for spread in self.spreads() if self._held is not None else ():
            rows = spread.nodes
            if spread is inter.mortar:
                c = inter.candidates
                rows = _node_rows(len(rows), np.concatenate([
                    np.repeat(c.slave, c.nodes.shape[1] - 1),
                    np.repeat(np.arange(len(rows)), rows.shape[1])]),
                    np.concatenate([c.nodes[:, :-1].ravel(), rows.ravel()]))
            keys.append(self._keys(rows[near.slave], near.nodes).ravel())
        pairs = np.unique(np.concatenate(keys))
        pairs = pairs[pairs >= 0]
        i = np.arange(d)
        rows = ((pairs // _WIDTH)[:, None, None] * d + i[:, None]).repeat(d, axis=2)
        cols = ((pairs % _WIDTH)[:, None, None] * d + i).repeat(d, axis=1)
        self._held = (pairs, rows.ravel(), cols.ravel())

    def _pair_index(self, keys: np.ndarray) -> np.ndarray:
        """Index among the pattern's node pairs of each of ``keys`` (any shape), -1 where a
        key is -1; refuses a key the pattern does not hold."""
        pairs, valid = self._held[0], keys >= 0
        at = np.searchsorted(pairs, keys).clip(max=max(len(pairs) - 1, 0))
        if valid.any() and (not len(pairs) or np.any(valid & (pairs[at] != keys))):
            raise RuntimeError(f"{self.name}: a contact coupling outside the matrix pattern "
                               f"(internal error: renew() was not called after a search)")
        return np.where(valid, at, -1)

    def _entry_slots(self, pair: np.ndarray) -> np.ndarray:
        """(n, r * d, c * d) indices among :meth:`couplings` of the entries of blocks whose
        node pairs have the indices ``pair`` (n, r, c) (-1: absent)."""
        d, (n, r, c) = self.gdim, pair.shape
        i = np.arange(d)
        slot = (pair[:, :, None, :, None] * d * d + i[:, None, None] * d + i).reshape(
            n, r * d, c * d)
        slot[np.broadcast_to(pair[:, :, None, :, None] < 0, (n, r, d, c, d)).reshape(
            slot.shape)] = -1
        return slot

    def _coupling_slots(self, candidate: np.ndarray) -> np.ndarray:
        """(len(candidate), nd, nd) the index among :meth:`couplings` of each entry of the
        tangents of the candidates numbered ``candidate`` (-1 where a rigid obstacle's node
        has no dofs): made for the evaluated elements only (few of a search's candidates)."""
        nodes = self.interaction.candidates.nodes[candidate]
        return self._entry_slots(self._pair_index(self._keys(nodes, nodes)))

    def node_dofs(self, nodes: np.ndarray, bcs: Sequence = ()) -> np.ndarray:
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

    def spreads(self) -> list:
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
        if self.spreads():
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
        spreads = self.spreads()
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
        slot = self._entry_slots(self._pair_index(self._keys(rows, cols)))
        masked = (self.node_dofs(rows, bcs)[:, :, None] < 0) | \
            (self.node_dofs(cols, bcs)[:, None, :] < 0)
        slot[masked] = -1
        return slot

    def _bc_dofs(self, bcs: Sequence) -> np.ndarray:
        """Sorted global dofs of the Dirichlet conditions ``bcs`` (all ranks; collective)."""
        held, dofs = self._bc_cache
        if len(held) == len(bcs) and all(a is b for a, b in zip(held, bcs)):
            return dofs
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
        self._bc_cache = (tuple(bcs), dofs)
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
            dofs = self.node_dofs(rows, bcs)
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
            r = self.node_dofs(rows, bcs).astype(PETSc.IntType)
            c = self.node_dofs(cols, bcs).astype(PETSc.IntType)
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
            dofs = self.node_dofs(rows)
            keep = dofs >= 0
            s.setValues(dofs[keep].astype(PETSc.IntType), roundoff.reshape(dofs.shape)[keep],
                        addv=PETSc.InsertMode.ADD)

    def couplings(self) -> tuple[np.ndarray, np.ndarray]:
        """Global ``(rows, cols)`` of every entry the contact tangent may fill until the
        pattern is renewed (:meth:`renew`), each once."""
        if self._held is None:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        return self._held[1], self._held[2]

    def coupling_values(self, bcs: Sequence = ()) -> np.ndarray:
        """Tangent values in the order of :meth:`couplings`: the sum of the elements'
        entries (0 where no element couples, and in the rows and columns of ``bcs``)."""
        el = self._evaluated()
        rows, _ = self.couplings()
        slot = self._coupling_slots(el.candidate)
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

    def coupling_entries(self) -> tuple[np.ndarray, np.ndarray]:
        """The current elements' tangents by their index among :meth:`couplings`:
        ``(index, values)``, ``index`` distinct (what :meth:`coupling_values` holds there,
        without ``bcs``; elsewhere it is zero)."""
        el = self._evaluated()
        slot = self._coupling_slots(el.candidate).ravel()
        K = self._own_part(el)[1].ravel()
        blocks = [(slot, K)] + [(self._block_slots(r, c, ()).ravel(), K_.ravel())
                                for r, c, _, K_, _ in self._spread_blocks()]
        index = np.concatenate([s for s, _ in blocks])
        values = np.concatenate([v for _, v in blocks])
        keep = index >= 0
        index, inverse = np.unique(index[keep], return_inverse=True)
        return index, np.bincount(inverse, weights=values[keep], minlength=len(index))

    def element_entries(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Global ``(rows, cols, values)`` of the current elements' tangents only (what
        :meth:`coupling_values` holds where it is not zero by construction; a rigid
        obstacle's rows and columns left out; no bcs)."""
        el = self._evaluated()
        blocks = [(el.nodes, el.nodes, self._own_part(el)[1])]
        blocks += [(r, c, K) for r, c, _, K, _ in self._spread_blocks()]
        out = []
        for r, c, K in blocks:
            r, c = self.node_dofs(r), self.node_dofs(c)
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
