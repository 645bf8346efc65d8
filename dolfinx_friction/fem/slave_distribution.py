"""Where a slave node's contact force acts on quadratic slave faces, over all ranks.

On linear faces, and against a deformable master with the nodal distribution, a slave
node's force acts on the node itself.  On quadratic faces against a rigid obstacle, or with
the mortar distribution (:mod:`~dolfinx_friction.contact.slave_weights`), node ``k``'s
force ``F_k`` acts on the nodes ``i`` of the faces around it, ``f_i = T_ik F_k`` with
``sum_i T_ik = 1``: its *star*.  The faces around an owned slave node may lie on other
ranks; their columns of ``C`` are sent to the node's owner.  The weights are measured on
the faces as deformed at the start of each increment (with the slave areas) and held
within it, so the contact tangent stays the exact derivative of the contact forces.
"""
from __future__ import annotations

import numpy as np

from dolfinx_friction.contact.shapes import FaceType
from dolfinx_friction.contact.slave_weights import distribution
from dolfinx_friction.fem.numbering import BodyField


def owner_ranks(field: BodyField, nodes: np.ndarray) -> np.ndarray:
    """The rank that owns each of the body's system nodes ``nodes`` (n,) (collective)."""
    first = int(field.nodes[0]) if field.n_owned else 0
    comm = field.V.mesh.comm
    ranges = np.array(comm.allgather((first, first + field.n_owned)), dtype=np.int64)
    owner = np.flatnonzero(ranges[:, 1] > ranges[:, 0])
    return owner[np.searchsorted(ranges[owner, 0], nodes, side="right") - 1]


class SpreadRows:
    """Rows of the system that the owned slave nodes' forces reach besides the elements'
    own: per slave node the nodes :attr:`nodes` (n, width; -1 beyond the last) and weights
    :attr:`weights` (n, width); node ``i`` of slave node ``k``'s row gets ``sign * w_ki F_k``
    (``sign``: +1 where it replaces the slave node's row, -1 the master's)."""

    sign = 1.0
    nodes: np.ndarray
    weights: np.ndarray

    def spread(self, slave: np.ndarray, force: np.ndarray, tangent: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """These rows of elements of the slave nodes ``slave`` (n,) whose slave-node force
        is ``force`` (n, d) with derivative ``tangent`` (n, d, c, d) over the elements'
        nodes: row nodes (n, width), forces (n, width, d) and tangents (n, width, d, c, d)."""
        W = self.sign * self.weights[slave]
        return (self.nodes[slave], W[:, :, None] * force[:, None, :],
                W[:, :, None, None, None] * tangent[:, None])


class SlaveDistribution(SpreadRows):
    """The stars of the owned slave nodes of one contact pair on this rank.

    ``field``: the slave body; ``face``: its (quadratic) face type; ``facet_nodes``
    (n_faces, nn): local nodes of the slave faces this rank holds; ``slaves`` (n,): the
    system node numbers of the slave nodes this rank owns.
    """

    def __init__(self, field: BodyField, face: FaceType, facet_nodes: np.ndarray,
                 slaves: np.ndarray):
        comm = field.V.mesh.comm
        self.comm, self.face, self._facet_nodes = comm, face, facet_nodes
        face_sys = field.nodes[facet_nodes]  # (n_faces, nn) system nodes
        k_sys = face_sys.ravel()  # one entry per (face, position): the node whose column
        owner = owner_ranks(field, k_sys)
        #: the entries sent to each rank, in the order of the values sent every increment
        self._order = np.argsort(owner, kind="stable")
        self._counts = np.bincount(owner, minlength=comm.size)
        nn = face.n_nodes
        rows = np.repeat(face_sys, nn, axis=0)[self._order]  # the face's nodes per entry
        received = comm.alltoall(self._split((k_sys[self._order], rows)))
        k_in = np.concatenate([r[0] for r in received]).astype(np.int64)
        i_in = np.concatenate([r[1] for r in received]).reshape(-1, nn).astype(np.int64)
        order = np.argsort(slaves)
        s_in = order[np.searchsorted(slaves, k_in, sorter=order)]  # slave index per entry
        # each slave's star: the distinct nodes of its faces, padded with -1
        keys = s_in[:, None] * (int(i_in.max(initial=0)) + 1) + i_in
        unique, position = np.unique(keys, return_inverse=True)
        owner_of = unique // (int(i_in.max(initial=0)) + 1)
        start = np.searchsorted(owner_of, np.arange(len(slaves)))
        rank_in_star = np.arange(len(unique)) - start[owner_of]
        width = int(rank_in_star.max(initial=-1)) + 1
        #: (n, width) system nodes of each owned slave node's star, -1 beyond its end
        self.nodes = np.full((len(slaves), width), -1, dtype=np.int64)
        self.nodes[owner_of, rank_in_star] = unique % (int(i_in.max(initial=0)) + 1)
        self._slot = (owner_of * width + rank_in_star)[position.reshape(-1)]
        #: (n, width) the weights ``T_ik`` (rows sum to 1), set by :meth:`update`
        self.weights = np.zeros(self.nodes.shape)

    def _split(self, arrays: tuple) -> list:
        """Arrays in send order cut into one tuple per destination rank."""
        ends = np.cumsum(self._counts)
        return [tuple(a[e - c:e] for a in arrays) for c, e in zip(self._counts, ends)]

    def update(self, x: np.ndarray) -> None:
        """The weights on the faces with the slave body's local nodes at ``x`` (n_local,
        gdim) (collective)."""
        C = distribution(self.face, x[self._facet_nodes])  # (n_faces, nn_i, nn_k)
        columns = np.transpose(C, (0, 2, 1)).reshape(-1, self.face.n_nodes)[self._order]
        received = self.comm.alltoall([part[0] for part in self._split((columns,))])
        values = np.concatenate(received).reshape(-1) if received else np.zeros(0)
        weights = np.zeros(self.nodes.size)
        np.add.at(weights, self._slot, values)
        weights = weights.reshape(self.nodes.shape)
        total = weights.sum(axis=1, keepdims=True)
        self.weights = np.divide(weights, total, out=np.zeros_like(weights), where=total > 0)
