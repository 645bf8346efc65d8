"""How a slave node's contact force reaches the master with ``distribution = "mortar"``.

Plain node-to-surface hands slave node ``k``'s force ``F_k`` to the nodes ``m`` of its
master face with the shape functions at its projection, ``N_m(eta_k)``.  The mortar
distribution hands it over with the weights

    W_km = int N_k(s) N_m(eta(s)) ds / sum_m' int N_k(s) N_m'(eta(s)) ds

over the slave faces around ``k`` (:func:`~dolfinx_friction.contact.mortar_weights.
mortar_integrals`), ``f_m = -W_km F_k`` (docs/theory.md §2.4): a uniform pressure then
loads the master with its consistent nodal forces.  The weights are measured on the
surfaces as deformed at the start of each increment (the converged state, as the slave
areas) and held within it: the tangent rows of the master are ``-W_km dF_k/du``.

Each rank integrates the slave faces it holds against the master faces near them (sent
by their ranks) and sends each node's integrals to the rank that owns the node.
"""
from __future__ import annotations

import numpy as np
from mpi4py import MPI
from scipy.spatial import cKDTree

from dolfinx_friction.contact.mortar_weights import mortar_integrals
from dolfinx_friction.contact.shapes import FACE_TYPES, FaceType, surface_vector
from dolfinx_friction.contact.slave_weights import SUBFACES, is_quadratic
from dolfinx_friction.fem.numbering import BodyField
from dolfinx_friction.fem.slave_distribution import SpreadRows, owner_ranks
from dolfinx_friction.fem.surfaces import MasterFaces


class MortarDistribution(SpreadRows):
    """The mortar weights of the owned slave nodes of one contact pair on this rank: the
    master rows of their elements get ``-W_km F_k`` (:meth:`~SpreadRows.spread`).

    ``field``: the slave body; ``face``: its face type (quadratic faces enter as their
    linear sub-faces, whose shape functions ``L_k`` take the place of ``N_k``, as in the
    slave areas: docs/theory.md §2.1); ``facet_nodes`` (n_faces, nn): local nodes of the
    slave faces this rank holds; ``slaves`` (n,): the system node numbers of the slave nodes
    this rank owns; ``master``: the master faces this rank holds.  On an axisymmetric body
    the integrals are over the revolved faces, and its (2D) quadratic faces keep their own
    shape functions, as its slave areas do.
    """

    sign = -1.0

    def __init__(self, field: BodyField, face: FaceType, facet_nodes: np.ndarray,
                 slaves: np.ndarray, master: MasterFaces):
        self._revolved = field.axisymmetric
        if is_quadratic(face) and not self._revolved:
            sub, corners = SUBFACES[face.name]
            facet_nodes = facet_nodes[:, np.array(corners)].reshape(-1, len(corners[0]))
            face = FACE_TYPES[sub]
        self.comm: MPI.Comm = field.V.mesh.comm
        self.face, self.master = face, master
        self._facet_nodes = facet_nodes
        self._face_sys = field.nodes[facet_nodes]  # (n_faces, nn) system nodes
        self._owner = owner_ranks(field, self._face_sys.ravel()).reshape(self._face_sys.shape)
        self._slaves = np.asarray(slaves, dtype=np.int64)
        #: (n, width) system nodes of the master nodes each owned slave node's force
        #: reaches, -1 beyond the last
        self.nodes = np.full((len(slaves), 0), -1, dtype=np.int64)
        #: (n, width) the weights ``W_km`` (rows sum to 1 where the node's faces meet the
        #: master, 0 elsewhere), set by :meth:`update`
        self.weights = np.zeros(self.nodes.shape)
        #: (n,) whether the node has weights; one without (its faces met no master face
        #: at the increment's start) hands its force over as with the nodal distribution
        self.covered = np.zeros(len(slaves), dtype=bool)

    def update(self, x_slave: np.ndarray, x_master: np.ndarray) -> None:
        """The weights with the slave body's local nodes at ``x_slave`` (n_local, gdim) and
        the held master faces' nodes at ``x_master`` (n_faces, nn_m, gdim) (collective)."""
        xs = x_slave[self._facet_nodes]
        xm, m_sys = self._near_master_faces(xs, x_master)
        s, m = _facing_pairs(self.face, xs, self.master.face, xm)
        integrals = mortar_integrals(self.face, xs[s], self.master.face, xm[m],
                                     self._revolved)
        k = np.broadcast_to(self._face_sys[s][:, :, None], integrals.shape).ravel()
        owner = np.broadcast_to(self._owner[s][:, :, None], integrals.shape).ravel()
        j = np.broadcast_to(m_sys[m][:, None, :], integrals.shape).ravel()
        value = integrals.ravel()
        keep = value != 0.0  # (negative at the corners of quadratic masters)
        k, owner, j, value = k[keep], owner[keep], j[keep], value[keep]
        order = np.argsort(owner, kind="stable")
        ends = np.cumsum(np.bincount(owner, minlength=self.comm.size))
        k, j, value = k[order], j[order], value[order]
        received = self.comm.alltoall([(k[e - c:e], j[e - c:e], value[e - c:e])
                                       for c, e in zip(np.diff(ends, prepend=0), ends)])
        k = np.concatenate([r[0] for r in received]).astype(np.int64)
        j = np.concatenate([r[1] for r in received]).astype(np.int64)
        value = np.concatenate([r[2] for r in received])
        self.nodes, self.weights = _rows(self._slaves, k, j, value)
        self.covered = self.weights.sum(axis=1) > 0.0

    def _near_master_faces(self, xs: np.ndarray, x_master: np.ndarray
                           ) -> tuple[np.ndarray, np.ndarray]:
        """The master faces (all ranks) whose boxes meet the box of this rank's slave faces
        ``xs`` (n, nn, gdim), inflated by twice the largest face: coordinates
        (n_m, nn_m, gdim) and system nodes (n_m, nn_m)."""
        size = 2.0 * self.comm.allreduce(max(_largest(xs), _largest(x_master)), op=MPI.MAX)
        box = None
        if len(xs):
            points = xs.reshape(-1, xs.shape[-1])
            box = np.stack([points.min(0) - size, points.max(0) + size])
        lo, hi = x_master.min(axis=1), x_master.max(axis=1)
        outgoing = []
        for b in self.comm.allgather(box):
            keep = (np.zeros(len(lo), bool) if b is None
                    else np.all((hi >= b[0]) & (lo <= b[1]), axis=1))
            outgoing.append((x_master[keep], self.master.nodes[keep]))
        incoming = self.comm.alltoall(outgoing)
        shape = x_master.shape[1:]
        return (np.concatenate([f[0] for f in incoming]).reshape(-1, *shape),
                np.concatenate([f[1] for f in incoming]).reshape(-1, shape[0]))


def _sizes(x: np.ndarray) -> np.ndarray:
    """The largest distance of a face node from its face's centroid (n,) (faces
    (n, nn, gdim))."""
    return np.linalg.norm(x - x.mean(axis=1, keepdims=True), axis=2).max(axis=1, initial=0.0)


def _largest(x: np.ndarray) -> float:
    return float(_sizes(x).max(initial=0.0))


def _facing_pairs(slave: FaceType, xs: np.ndarray, master: FaceType, xm: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """(slave face, master face) pairs that may overlap: normals facing each other,
    centroids closer than 1.5 times the sum of the two faces' sizes, the slave centroid
    within that sum of the master face's plane (farther faces are open: their nodes hand
    their forces over as with the nodal distribution until the next increment)."""
    if not len(xs) or not len(xm):
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    c_s, c_m = xs.mean(axis=1), xm.mean(axis=1)
    size_s, size_m = _sizes(xs), _sizes(xm)
    near = cKDTree(c_m).query_ball_point(c_s, 1.5 * (size_s + size_m.max()))
    s = np.repeat(np.arange(len(xs)), [len(n) for n in near])
    m = np.concatenate([np.asarray(n, dtype=np.int64) for n in near] + [np.zeros(0, np.int64)])
    n_m = _normals(master, xm)
    n_m /= np.linalg.norm(n_m, axis=1)[:, None]
    reach = size_s[s] + size_m[m]
    gap = np.abs(np.einsum("nd,nd->n", c_s[s] - c_m[m], n_m[m]))
    keep = ((np.einsum("nd,nd->n", _normals(slave, xs)[s], n_m[m]) < 0.0)
            & (np.linalg.norm(c_s[s] - c_m[m], axis=1) <= 1.5 * reach) & (gap <= reach))
    return s[keep], m[keep]


def _normals(face: FaceType, x: np.ndarray) -> np.ndarray:
    """Surface vectors (n, gdim) at the faces' centroids (faces (n, nn, gdim))."""
    _, dphi, _ = face.evaluate(face.centroid[None])
    return surface_vector(np.einsum("ka,nkd->nad", dphi[0], x))


def _rows(slaves: np.ndarray, k: np.ndarray, j: np.ndarray, value: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray]:
    """The integrals ``value`` of slave system nodes ``k`` against master system nodes
    ``j`` (m,) summed per pair and normalised per slave node: nodes and weights
    (len(slaves), width), -1 and 0 beyond each row's end."""
    order = np.argsort(slaves)
    row = order[np.searchsorted(slaves, k, sorter=order)]  # slave index per entry
    width = int(j.max(initial=0)) + 1
    keys, inverse = np.unique(row * width + j, return_inverse=True)
    sums = np.bincount(inverse, weights=value, minlength=len(keys))
    owner_of, master = keys // width, keys % width
    start = np.searchsorted(owner_of, np.arange(len(slaves)))
    rank = np.arange(len(keys)) - start[owner_of]
    columns = int(rank.max(initial=-1)) + 1
    nodes = np.full((len(slaves), columns), -1, dtype=np.int64)
    weights = np.zeros((len(slaves), columns))
    nodes[owner_of, rank], weights[owner_of, rank] = master, sums
    total = weights.sum(axis=1, keepdims=True)
    return nodes, np.divide(weights, total, out=np.zeros_like(weights), where=total > 0)
