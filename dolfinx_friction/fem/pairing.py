"""One contact pair at run time: search, pairing, element evaluation, slave history.

Each rank evaluates the elements of the slave nodes it owns.  Before each
pairing it receives only the master faces whose bounding boxes meet the
(inflated) bounding box of its slave nodes; the displacements of their nodes,
and of the slave nodes, are gathered from the system vector by a PETSc
scatter.  Forces and tangents go back by global index (ADD).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Union

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc
from scipy.spatial import cKDTree

from dolfinx_friction.contact.element import (OPEN, SLIP, STICK, ContactParameters, ElementResult,
                                              Kinematics, evaluate, face_kinematics,
                                              rigid_kinematics, sdf_kinematics)
from dolfinx_friction.contact.friction import FrictionState
from dolfinx_friction.contact.projection import clearances
from dolfinx_friction.fem.contact_settings import MAX_RELAXATION
from dolfinx_friction.fem.mortar_distribution import MortarDistribution
from dolfinx_friction.fem.obstacles import (Obstacle, SignedDistance, rotation_matrix,
                                             rotation_size)
from dolfinx_friction.fem.surfaces import MasterFaces, SlaveNodes


class _Prescribed:
    """Stands in for :class:`NodeValues` for a rigid obstacle without dofs: its
    translation, whatever the vector."""

    def __init__(self, master: RigidMaster):
        self.master = master

    def __call__(self, vec: PETSc.Vec) -> np.ndarray:
        return np.asarray(self.master.translation, dtype=float).reshape(1, -1).copy()


class NodeValues:
    """Values of a distributed system vector at chosen nodes, gathered from their owners."""

    def __init__(self, template: PETSc.Vec, nodes: np.ndarray, gdim: int):
        idx = (np.asarray(nodes, dtype=np.int64).reshape(-1, 1) * gdim + np.arange(gdim)).ravel()
        self.gdim = gdim
        start, end = template.getOwnershipRange()
        #: entries gathered from other ranks at each call
        self.remote = int(np.count_nonzero((idx < start) | (idx >= end)))
        self.local = PETSc.Vec().createSeq(len(idx), comm=PETSc.COMM_SELF)
        index_set = PETSc.IS().createGeneral(idx.astype(PETSc.IntType), comm=PETSc.COMM_SELF)
        self.scatter = PETSc.Scatter().create(template, index_set, self.local, None)

    def __call__(self, vec: PETSc.Vec) -> np.ndarray:
        self.scatter.scatter(vec, self.local, addv=PETSc.InsertMode.INSERT,
                             mode=PETSc.ScatterMode.FORWARD)
        return self.local.getArray(readonly=True).reshape(-1, self.gdim).copy()


@dataclass
class RigidMaster:
    """An analytic rigid obstacle whose translation is system node ``node``, or, with
    ``node = None``, the prescribed ``translation`` (gdim,) (no dofs: its element
    couples the slave node alone).  Its ``rotation`` (1 component in 2D, 3 in 3D, about
    the obstacle's :attr:`~dolfinx_friction.fem.obstacles.Obstacle.pivot`) is prescribed;
    ``rotation_n`` and ``translation_n`` are the pose at the last commit (the increment's
    start)."""

    rigid: Union[Obstacle, SignedDistance]
    node: Optional[int] = None
    translation: Optional[np.ndarray] = None
    rotation: Optional[np.ndarray] = None
    rotation_n: Optional[np.ndarray] = None
    translation_n: Optional[np.ndarray] = None

    def __post_init__(self) -> None:
        d = len(self.translation)
        self.rotation = np.zeros(rotation_size(d)) if self.rotation is None else self.rotation
        self.rotation_n = self.rotation.copy()
        self.translation_n = self.translation.copy()

    def kinematics(self, X: np.ndarray, u: np.ndarray, U: np.ndarray,
                   rotation: Optional[np.ndarray] = None) -> Kinematics:
        """Kinematics against the obstacle turned by ``rotation`` (default: the current
        one) and translated by ``U`` (gdim,)."""
        r = self.rigid
        turned = self.rotation if rotation is None else rotation
        if isinstance(r, SignedDistance):
            return sdf_kinematics(X, u, U, r.distance, r.gradient, r.hessian,
                                  rotation_matrix(turned, len(U)), r.pivot)
        if not turned.any():
            return rigid_kinematics(r.shape, X, u, U, point=r.point, normal=r.normal,
                                    center=r.center, axis=r.axis, radius=r.radius or 0.0)
        return rigid_kinematics(r.shape, X, u, U, **r.moved(rotation_matrix(turned, len(U))))

    @property
    def rotating(self) -> bool:
        """Whether the obstacle turns in this increment."""
        return bool(np.any(self.rotation != self.rotation_n))

    def slip_offset(self, X: np.ndarray, u_n: np.ndarray, U_n: np.ndarray) -> np.ndarray:
        """(n, gdim) motion since the increment's start, beyond its translation, of the
        obstacle's material points under slave nodes at reference ``X`` displaced by ``u_n``
        (n, gdim) at the start, the obstacle then translated by ``U_n``:
        ``(Q - Q_n)(X_m - c)``, ``X_m`` the point under the node in the reference shape,
        ``c`` the pivot.  Constant in the unknowns."""
        d = len(U_n)
        kin = self.kinematics(X, u_n, U_n, self.rotation_n)
        q_n = X + u_n - kin.g_N[:, None] * kin.normal  # the point under the node, at the start
        Q, Q_n = rotation_matrix(self.rotation, d), rotation_matrix(self.rotation_n, d)
        arm = q_n - np.asarray(self.rigid.pivot, float) - U_n  # Q_n (X_m - c)
        return arm @ (Q @ Q_n.T - np.eye(d)).T

    def commit(self, U: np.ndarray) -> None:
        """The pose of the converged increment (translation ``U``) becomes the start pose."""
        self.rotation_n = self.rotation.copy()
        self.translation_n = np.asarray(U, float).copy()


@dataclass
class Exchange:
    """What this rank's part of a pair sent and received for its searches, in bytes of the
    arrays (without MPI's and pickle's envelopes): the search's box exchange is an
    allgather (each rank receives every rank's box, 2 gdim floats), the master faces go
    point to point (alltoall; a face: its node numbers, reference coordinates, global id).
    ``gathered``: displacement values this rank gathers from other ranks at every
    evaluation since the last search (its slave nodes' and the received faces' nodes)."""

    searches: int = 0
    box_bytes: int = 0  # received in the boxes' allgathers
    faces_sent: int = 0  # to other ranks
    face_bytes_sent: int = 0
    faces_received: int = 0  # from other ranks
    face_bytes_received: int = 0
    faces: int = 0  # held after the last search (this rank's and received)
    gathered: int = 0


@dataclass
class _Candidates:
    """Possible (slave node, master) pairs of an increment."""

    slave: np.ndarray  # indices into the pair's slave nodes
    face: np.ndarray  # rows of the received master faces (-1 for rigid)
    nodes: np.ndarray  # (n, nodes) system nodes of each candidate element


@dataclass
class Elements:
    """The current elements of a pair: which slaves, which master, and their results."""

    slave: np.ndarray  # indices into the pair's slave nodes
    face: np.ndarray  # row of the master face in the received face set (-1 for rigid)
    nodes: np.ndarray  # (n, nodes) system nodes of each element
    face_id: np.ndarray  # global number of each element's master face (-1 for rigid)
    candidate: np.ndarray  # index of each element among the pair's candidates
    xi: Optional[np.ndarray] = None  # last projection point, a start for the next one
    result: Optional[ElementResult] = None
    roundoff: Optional[np.ndarray] = None  # (n, nodes * gdim) round-off scale of the forces
    normal: Optional[np.ndarray] = None  # (n, gdim) unit contact normals at the evaluation
    phi: Optional[np.ndarray] = None  # (n, nodes) master weights at xi, -1 for the slave node


#: Parametric distance by which a slave node may pass its current face's edge and keep
#: that face during an increment (hysteresis against switching between faces).
FACE_SLACK = 1e-3
#: A slave node that projects inside no face (near a convex edge of a faceted master)
#: takes the nearest face it misses by at most this parametric distance.
EDGE_SLACK = 0.05
#: Candidate master faces per slave node (the nearest centroids), by dimension.
CANDIDATES = {2: 6, 3: 16}
#: Faces per slave node of the wider search whose couplings a matrix pattern holds
#: (:attr:`ContactInteraction.neighbourhood`): one face more on every side.
NEIGHBOURHOOD = {2: 10, 3: 36}
#: Ties in pairing: a node this close (parametric) to a face's edge projects inside it,
#: and clearances that differ by less than this times the node spacing are equal; ties go
#: to the face whose reference centroid (rounded to 1e3 TIE spacings) comes first (x, y,
#: z).  So a node on an edge shared by two faces picks the same face whatever the
#: partition (round-off and global face numbers differ between partitions).
TIE = 1e-9


class ContactInteraction:
    """Runtime state of one contact pair on this rank (``mortar``: the weights that hand
    the slave nodes' forces to the master, None: the master face's shape functions)."""

    def __init__(self, comm: MPI.Comm, name: str, params: ContactParameters,
                 slaves: SlaveNodes, master: Union[MasterFaces, RigidMaster], gdim: int,
                 pairing_iterations: int = 8, mortar: Optional[MortarDistribution] = None):
        self.comm, self.name, self.params, self.gdim = comm, name, params, gdim
        self.slaves, self.master, self.mortar = slaves, master, mortar
        self.pairing_iterations = pairing_iterations
        n = len(slaves.nodes)
        self.history = FrictionState.zeros(n, gdim)
        self.in_contact = np.zeros(n, dtype=bool)  # had an element at the last commit
        self.closed = np.zeros(n, dtype=bool)  # closed (not open) at the last commit
        self.lost = np.zeros(n, dtype=bool)  # projected onto no candidate at the last pairing
        self.off_surface = np.zeros(n, dtype=bool)  # lost even after a search, this increment
        self._gap_offset = np.zeros(0)  # ramp offset of the current elements' clearances
        self.cutoff = params.law.cutoff(slaves.area)
        self.initial_gap = np.zeros(n)  # negative clearances found at the first pairing (§3.4)
        #: augmented Lagrangian multipliers per slave node, as lengths (:meth:`augment`):
        #: ``lambda_N / K`` shifts the overclosure the law sees, ``lambda_T / (lambda A)``
        #: the reference of the elastic slip; zero for the penalty method
        self.multiplier_N = np.zeros(n)
        self.multiplier_T = np.zeros((n, gdim))
        #: this increment's last Uzawa step (normal, tangential) and its relaxation factors
        #: (:meth:`augment`)
        self._last_step: Optional[tuple[tuple[np.ndarray, np.ndarray],
                                        tuple[float, float]]] = None
        self._first_pairing = True
        self.elements = Elements(*(np.zeros(0, int),) * 2, np.zeros((0, 2), int),
                                 *(np.zeros(0, int),) * 2)
        self.candidates = _Candidates(np.zeros(0, int), np.zeros(0, int), np.zeros((0, 2), int))
        #: the candidates of a wider search at the last search (every candidate among them):
        #: the couplings a matrix pattern is made for, so that it serves the searches of the
        #: next increments of a slide while their candidates stay among these
        self.neighbourhood = self.candidates
        self._faces: Optional[tuple[np.ndarray, np.ndarray]] = None  # received (nodes, X)
        self._face_ids = np.zeros(0, dtype=np.int64)  # global ids of the received faces
        self._centroids = np.zeros((0, gdim))  # their reference centroids (ties in pairing)
        # (n_candidates, fdim) last projection points: the next pairing's starts
        self._xi = np.zeros((0, 0 if self.rigid else master.face.fdim))
        #: the search's communication so far, this rank
        self.exchange = Exchange()
        self._gather: Optional[NodeValues] = None
        self._slave_gather: Optional[NodeValues] = None
        self._trial: Optional[FrictionState] = None
        #: a rigid master's translation at the last evaluation (gdim,)
        self.master_motion: Optional[np.ndarray] = None

    @property
    def rigid(self) -> bool:
        return isinstance(self.master, RigidMaster)

    # ------------------------------------------------------------------ search
    def _exchange_faces(self, u_faces_local: np.ndarray, x_slaves: np.ndarray) -> None:
        """Receive the master faces near this rank's slave nodes from every rank."""
        m: MasterFaces = self.master
        x_faces = m.X + u_faces_local
        size = _face_size(x_faces)
        radius = 2.0 * self.comm.allreduce(size.max(initial=0.0), op=MPI.MAX)
        if len(x_slaves):
            box = np.stack([x_slaves.min(0) - radius, x_slaves.max(0) + radius])
        else:
            box = None
        boxes = self.comm.allgather(box)
        lo, hi = x_faces.min(axis=1), x_faces.max(axis=1)
        outgoing = []
        for b in boxes:
            keep = (np.zeros(len(lo), bool) if b is None
                    else np.all((hi >= b[0]) & (lo <= b[1]), axis=1))
            outgoing.append((m.nodes[keep], m.X[keep], m.ids[keep]))
        incoming = self.comm.alltoall(outgoing)
        ex, me = self.exchange, self.comm.rank
        ex.searches += 1
        ex.box_bytes += sum(0 if b is None else b.nbytes for b in boxes)
        for k, (out, into) in enumerate(zip(outgoing, incoming)):
            if k != me:
                ex.faces_sent += len(out[2])
                ex.face_bytes_sent += sum(a.nbytes for a in out)
                ex.faces_received += len(into[2])
                ex.face_bytes_received += sum(a.nbytes for a in into)
        nodes = np.concatenate([f[0] for f in incoming]).reshape(-1, m.face.n_nodes)
        X = np.concatenate([f[1] for f in incoming]).reshape(-1, m.face.n_nodes, self.gdim)
        self._faces = (nodes, X)
        self._centroids = X.mean(axis=1)
        self._face_ids = np.concatenate([f[2] for f in incoming])

    def measure_areas(self) -> None:
        """The slave areas, and the cutoff that scales with them, on the faces as the slave
        body's Function deforms them (collective): at the start of an increment."""
        self.slaves.update_areas()
        self.cutoff = self.params.law.cutoff(self.slaves.area)

    def search(self, u: PETSc.Vec, u_faces_local: Optional[np.ndarray],
               first: bool = True) -> None:
        """Candidate masters of every slave node (collective).

        Called once per increment (``first``), and again within it only when a slave
        node slides past all its candidates (:meth:`needs_search`).  Receives the master
        faces near this rank's slave nodes and keeps, for each slave node, the faces
        with the nearest centroids: pairing chooses among them, so the matrix pattern of
        the contact couplings changes only with a search.
        """
        if self._slave_gather is None:
            self._slave_gather = NodeValues(u, self.slaves.nodes, self.gdim)
        if first:
            self.off_surface[:] = False
        n = len(self.slaves.nodes)
        if self.rigid:
            node = self.master.node
            if self._gather is None:
                self._gather = (_Prescribed(self.master) if node is None
                                else NodeValues(u, np.array([node]), self.gdim))
            self.candidates = _Candidates(np.arange(n), np.full(n, -1), np.stack(
                [np.full(n, -1 if node is None else node), self.slaves.nodes], axis=1))
            self.neighbourhood = self.candidates
            return
        keys, xi = self._candidate_keys(), self._xi
        x_s = self.slaves.X + self._slave_gather(u)
        self._exchange_faces(u_faces_local, x_s)
        self._gather = NodeValues(u, self._faces[0].ravel(), self.gdim)
        face_nodes, X_f = self._faces
        self.exchange.faces = len(face_nodes)
        self.exchange.gathered = self._slave_gather.remote + self._gather.remote
        x_f = X_f + self._gather(u).reshape(X_f.shape)
        slave, face = _nearest_faces(x_s, x_f, CANDIDATES[self.gdim])
        nodes = np.concatenate([face_nodes[face], self.slaves.nodes[slave, None]], axis=1)
        self.candidates = _Candidates(slave, face, nodes)
        near_slave, near = _nearest_faces(x_s, x_f, NEIGHBOURHOOD[self.gdim])
        self.neighbourhood = _Candidates(near_slave, near, np.concatenate(
            [face_nodes[near], self.slaves.nodes[near_slave, None]], axis=1))
        # a candidate kept by the search starts from its last projection point
        self._xi = np.tile(self.master.face.centroid, (len(slave), 1))
        _, new, old = np.intersect1d(self._candidate_keys(), keys, assume_unique=True,
                                     return_indices=True)
        self._xi[new] = xi[old]

    def _candidate_keys(self) -> np.ndarray:
        """(n_candidates,) a unique number of each candidate's slave node and global face id."""
        c = self.candidates
        return c.slave.astype(np.int64) << 32 | self._face_ids[c.face]

    def pair(self, u: PETSc.Vec, iteration: int) -> None:
        """Pair every slave node with one of its candidate masters within the cutoff
        (beyond the clearance its augmented multiplier ``multiplier_N`` closes).

        A slave node takes the nearest face onto which it projects orthogonally.
        Pairing has hysteresis: within an increment (``iteration > 0``) a node with
        an element keeps one even above the cutoff, and keeps its face while it
        still projects onto it (up to :data:`FACE_SLACK` past its edges); a node
        that projects onto none of its candidates keeps the one it misses least
        (and is marked :attr:`lost`, which asks for a new search).  So elements are
        dropped only at the first pairing of an increment.  With a single pairing
        per increment, nodes closed at the last commit also keep an element then,
        however far the predictor has moved them.

        Each candidate is projected from its last projection point (:meth:`_project`).
        Only stationary points within EDGE_SLACK of a face count, but for the least missed
        faces of lost nodes, which are projected from the centroids: so the elements are
        those of projections from the centroids wherever a candidate's stationary point is
        unique and, when within EDGE_SLACK of the face, reached from the centroid.
        """
        cands = self.candidates
        u_s = self._slave_gather(u)
        n = len(self.slaves.nodes)
        had = np.zeros(n, dtype=bool)  # must keep an element
        if iteration > 0:
            had[self.elements.slave] = True
        elif self.pairing_iterations == 1:
            had |= self.closed
        if self.rigid:
            kin = self.master.kinematics(self.slaves.X, u_s, self._gather(u)[0])
            chosen = np.flatnonzero((kin.g_N <= self.cutoff + self.multiplier_N) | had)
            self._set_elements(chosen, np.zeros((len(chosen), 0)))
            return
        slave, cand = cands.slave, cands.face
        x_s = self.slaves.X + u_s
        x_f = self._faces[1] + self._gather(u).reshape(self._faces[1].shape)
        previous = np.full(n, -1, dtype=np.int64)
        if iteration > 0:
            previous[self.elements.slave] = self.elements.face_id
        # a node that keeps its face (rank 0 below; face ids are unique) wins whatever its
        # other candidates: they stay unprojected (outside = inf, as if Newton had failed),
        # which changes neither its choice nor near (lost and fallback then do not apply)
        current = self._face_ids[cand] == previous[slave]
        outside, g_N = np.full(len(slave), np.inf), np.full(len(slave), np.inf)
        self._project(x_s, x_f, np.flatnonzero(current), outside, g_N)
        kept = np.zeros(n, dtype=bool)
        kept[slave[current & (outside <= FACE_SLACK)]] = True
        self._project(x_s, x_f, np.flatnonzero(~current & ~kept[slave]), outside, g_N)
        near = np.zeros(n, dtype=bool)  # projects onto a candidate (up to EDGE_SLACK)
        near[slave[outside <= EDGE_SLACK]] = True
        expected = had | self.closed if iteration == 0 else had
        self.lost = expected & ~near
        # the least missed faces of lost nodes compare far misses (rank 3 below): those from
        # the centroids, as warm starts converge on misses a cold start may not reach
        self._project(x_s, x_f, np.flatnonzero((self.lost & had)[slave]), outside, g_N, cold=True)
        # preference: the current face (within FACE_SLACK), an interior projection, a near
        # miss, the least missed face of a lost node; then the smallest clearance, then the
        # first reference centroid (TIE)
        rank = np.where(outside <= TIE, 1, 2)
        rank[current & (outside <= FACE_SLACK)] = 0
        rank[outside > EDGE_SLACK] = 3
        fallback = (self.lost & had)[slave] & np.isfinite(outside)
        reach = self.cutoff[slave] + self.multiplier_N[slave]
        ok = np.flatnonzero(((outside <= EDGE_SLACK) & ((g_N <= reach) | had[slave]))
                            | fallback)
        unit = TIE * self.slaves.spacing[slave[ok]]
        clearance = np.floor(np.where(rank[ok] == 3, outside[ok] / TIE, np.abs(g_N[ok]) / unit))
        centroid = np.round(self._centroids[cand[ok]] / (1e3 * unit[:, None]))
        order = ok[np.lexsort((*centroid.T[::-1], clearance, rank[ok], slave[ok]))]
        chosen = order[np.unique(slave[order], return_index=True)[1]]
        self._set_elements(chosen, self._xi[chosen])

    def closed_change(self, u: PETSc.Vec, u_n: PETSc.Vec, ramp: float) -> int:
        """How many slave nodes a first pairing at ``u`` (as at the start of an increment),
        evaluated there, closes or opens against the current elements' evaluation.  The
        current elements, their evaluation and the projections' starts stay as they are.
        Collective; the count is this rank's."""
        kept = (self.elements, self.lost, self._xi.copy(), self._trial, self._gap_offset,
                self.master_motion)
        closed = self._closed_nodes()
        self.pair(u, 0)
        self.evaluate(u, u_n, ramp)
        changed = len(np.setxor1d(self._closed_nodes(), closed))
        (self.elements, self.lost, self._xi, self._trial, self._gap_offset,
         self.master_motion) = kept
        return changed

    def _closed_nodes(self) -> np.ndarray:
        """The slave nodes whose current element is evaluated closed."""
        el = self.elements
        if el is None or el.result is None:
            return np.zeros(0, dtype=np.int64)
        return el.slave[el.result.status != OPEN]

    def _project(self, x_s: np.ndarray, x_f: np.ndarray, rows: np.ndarray, outside: np.ndarray,
                 g_N: np.ndarray, cold: bool = False) -> None:
        """Project the candidates ``rows`` (slave points ``x_s`` (n, gdim) onto the received
        faces ``x_f`` (n_faces, nn, gdim)) from their last projection points (``cold``: from
        the centroid); fills ``outside`` and ``g_N`` (n_candidates,) at ``rows``.

        Where Newton fails from a last point, the centroid's answer counts; the next start is
        still the last point unless that answer converged (so a far miss converges over
        pairings)."""
        c, face = self.candidates, self.master.face
        centroid = np.tile(face.centroid, (len(rows), 1))
        xi0 = centroid if cold else self._xi[rows]
        xi, out, g = clearances(face, x_s, x_f, c.slave[rows], c.face[rows], xi0)
        again = np.flatnonzero(np.isinf(out) & np.any(xi0 != centroid, axis=1))
        xi_c, out_c, g_c = clearances(face, x_s, x_f, c.slave[rows[again]], c.face[rows[again]],
                                      centroid[again])
        won = np.isfinite(out_c)
        xi[again[won]], out[again[won]], g[again[won]] = xi_c[won], out_c[won], g_c[won]
        self._xi[rows], outside[rows], g_N[rows] = xi, out, g

    def slave_displacements(self, u: PETSc.Vec) -> np.ndarray:
        """(n, gdim) displacements of this rank's slave nodes in the system vector ``u``."""
        return self._slave_gather(u)

    def needs_search(self) -> bool:
        """Whether a node projects onto none of its candidates since the last search (it
        may have slid past them all: a new search finds its face, or marks it
        :attr:`off_surface`).  Local: the caller reduces over ranks."""
        return bool((self.lost & ~self.off_surface).any())

    def mark_off_surface(self) -> None:
        """After a search and pairing: nodes still lost have left the master surface."""
        self.off_surface |= self.lost

    def _set_elements(self, chosen: np.ndarray, xi: np.ndarray) -> None:
        """Make the chosen candidates (projected at ``xi``) the current elements."""
        c = self.candidates
        face_id = self._face_ids[c.face[chosen]] if not self.rigid else np.full(len(chosen), -1)
        self.elements = Elements(c.slave[chosen], c.face[chosen], c.nodes[chosen], face_id,
                                 chosen, xi)
        self._record_initial_gaps()

    def _record_initial_gaps(self) -> None:
        """At the very first pairing, keep the overclosures of the reference configuration."""
        if not self._first_pairing:
            return
        self._first_pairing = False
        el = self.elements
        zero = np.zeros((len(self.slaves.X), self.gdim))
        n_master = 1 if self.rigid else self._faces[0].size
        u_master = np.zeros((n_master, self.gdim))
        g0 = self._kinematics(el, np.arange(len(el.slave)), zero, u_master).g_N
        self.initial_gap[el.slave] = np.minimum(g0, 0.0)

    # -------------------------------------------------------------- evaluation
    def evaluate(self, u: PETSc.Vec, u_n: PETSc.Vec, ramp: float = 0.0) -> Elements:
        """Element forces and tangents at the iterate ``u`` (start of increment ``u_n``).

        ``ramp`` is the share ``1 - tau`` of the initial overclosure still removed from
        the clearance (first static step, docs/theory.md §3.4).  Collective: every
        rank gathers, whether or not it has elements.
        """
        el = self.elements
        s = el.slave
        every = np.arange(len(s))
        u_slaves = self._slave_gather(u)
        kin = self._kinematics(el, every, u_slaves, self._gather(u), el.xi)
        el.xi, el.normal, el.phi = kin.xi, kin.normal, kin.phi
        history = None
        if self.params.mu > 0.0:
            history = self.history.take(s)
            new = np.flatnonzero(~self.in_contact[s])  # first touch: s = 0 from the start state
            u_s, u_m = self._slave_gather(u_n), self._gather(u_n)  # collective: always gather
            history.w[new] = self._kinematics(el, new, u_s, u_m, el.xi[new]).w
            history.g_T[new] = 0.0
            history.g_p[new] = 0.0
            history.g_p -= self.multiplier_T[s]  # the elastic slip measured from its shift
            if self.rigid and self.master.rotating:
                # the obstacle's material point under a node moved with its rotation too:
                # s = w - (w_n + offset) (w = u_p - U holds the translation only).  A node
                # touching anew measures from the obstacle's translation its w_n holds: the
                # start's (an unknown translation), or the current one (prescribed), so with
                # the start's rotation or with the current one (no offset)
                old = np.flatnonzero(self.in_contact[s] | (self.master.node is not None))
                U_n = self.master.translation_n if self.master.node is None else u_m[0]
                history.w[old] += self.master.slip_offset(self.slaves.X[s[old]], u_s[s[old]],
                                                          U_n)
        self._gap_offset = -ramp * self.initial_gap[s]
        el.result = evaluate(kin, self.slaves.area[s], self.params, history,
                             gap_offset=self._gap_offset - self.multiplier_N[s])
        self.master_motion = self._gather(u)[0] if self.rigid else None
        self._trial = el.result.trial
        if self._trial is not None:
            self._trial.g_p += self.multiplier_T[s]
        # the clearance is a difference of coordinates: its round-off, times the tangent
        size = np.abs(self.slaves.X[s] + u_slaves[s]).max(axis=1, initial=0.0)
        nd = el.nodes.shape[1] * self.gdim
        el.roundoff = (np.abs(el.result.K.reshape(-1, nd, nd)).sum(axis=2) * size[:, None]
                       + np.abs(el.result.f.reshape(-1, nd)))
        return el

    def normal_model(self) -> Optional[tuple]:
        """The frictionless elements at their last evaluation as a bilinear law of affine
        overclosures (:meth:`~dolfinx_friction.contact.laws.Law.bilinear`): ``(a, d, k, s,
        width, closed)``, the overclosures' gradients (n, nodes, gdim) on the elements'
        nodes (normals frozen: ``phi n``), the overclosures the law sees (n,) [length], ``k``,
        ``s`` (n,), the law's ``width`` and whether each is closed; None with friction or
        another law."""
        el, law = self.elements, self.params.law
        model = law.bilinear(self.slaves.area[el.slave]) if self.params.mu == 0.0 else None
        if model is None or el.result is None:
            return None
        a = el.phi[:, :, None] * el.normal[:, None, :]
        d = -(el.result.g_N + self._gap_offset - self.multiplier_N[el.slave])
        return a, d, *model, el.result.status != OPEN

    def _kinematics(self, el: Elements, rows: np.ndarray, u_slaves: np.ndarray,
                    u_master: np.ndarray, xi0: Optional[np.ndarray] = None) -> Kinematics:
        """Kinematics of some elements, from gathered slave and master displacements."""
        s = el.slave[rows]
        X_s, u_s = self.slaves.X[s], u_slaves[s]
        if self.rigid:
            return self.master.kinematics(X_s, u_s, u_master[0])
        _, X_f = self._faces
        f = el.face[rows]
        return face_kinematics(self.master.face, X_s, u_s, X_f[f],
                               u_master.reshape(X_f.shape)[f], xi0, tangent=self.params.tangent)

    # ---------------------------------------------------------------- history
    def commit(self) -> None:
        """Make the trial history of the converged increment the new start state."""
        self._last_step = None
        s = self.elements.slave
        self.in_contact[:] = False
        self.in_contact[s] = True
        self.closed[:] = False
        if self.elements.result is not None:
            self.closed[s] = self.elements.result.status != OPEN
        if self._trial is not None:
            fresh = FrictionState.zeros(len(self.in_contact), self.gdim)
            fresh.put(s, self._trial)
            self.history = fresh
        if self.rigid and self.master_motion is not None:
            self.master.commit(self.master_motion)
        self.multiplier_N[~self.in_contact] = 0.0  # a node that touches anew starts at 0
        self.multiplier_T[~self.in_contact] = 0.0

    def _uzawa(self) -> tuple[np.ndarray, np.ndarray]:
        """The augmented Lagrangian multipliers after one Uzawa update at the last
        evaluation (docs/theory.md §6.5), as lengths per slave node: ``lambda_N <- max(0,
        lambda_N + K d)`` with ``d`` the overclosure (the multiplier shifts the law's
        argument by ``lambda_N / K``), ``lambda_T <- F_T`` (the friction force: inside the
        Coulomb cone the stick's elastic slip goes into the multiplier); zero for nodes
        without an element."""
        el, r = self.elements, self.elements.result
        N, T = np.zeros_like(self.multiplier_N), np.zeros_like(self.multiplier_T)
        if r is not None and len(el.slave):
            s = el.slave
            N[s] = np.maximum(0.0, self.multiplier_N[s] - (r.g_N + self._gap_offset))
            if self.params.mu > 0.0:
                T[s] = r.F_T / (self.params.stick_slope * self.slaves.area[s])[:, None]
        return N, T

    def violation(self) -> float:
        """What the next Uzawa update would change, on this rank: the largest change of a
        multiplier as a length (the overclosure, the elastic slip of a sticking node)
        relative to the node's spacing."""
        N, T = self._uzawa()
        change = np.abs(N - self.multiplier_N)
        stick = self._sticking()
        change[stick] = np.maximum(change[stick], np.linalg.norm(
            T[stick] - self.multiplier_T[stick], axis=1))
        return float(np.max(change / self.slaves.spacing, initial=0.0))

    def _sticking(self) -> np.ndarray:
        """The slave nodes (indices) that stuck at the last evaluation."""
        el, r = self.elements, self.elements.result
        return el.slave[r.status == STICK] if r is not None else np.zeros(0, int)

    def augment(self) -> None:
        """Make the Uzawa update (:meth:`_uzawa`), over-relaxed by Aitken's factors from
        this increment's last two steps (collective); the elements must be evaluated again.

        Uzawa's iteration ``m <- m + r(m)`` converges like a geometric series of ratio
        ``rho = 1 / (1 + K / k_s)`` (``k_s``: the structure's stiffness at a node) for the
        overclosures, ``1 / (1 + lambda / k_s)`` for the elastic slips of sticking nodes:
        slowly where the penalty or the stick slope is soft.  Aitken's factor ``omega =
        -omega_last (r_last . (r - r_last)) / |r - r_last|^2`` (Irons and Tuck) is ``1 / (1 -
        rho)`` on such a series, its sum in one step; one for each part, held to ``[1,
        MAX_RELAXATION]``.  A slipping node's multiplier is its friction force, taken as it
        is."""
        N, T = self._uzawa()
        step_N, step_T = N - self.multiplier_N, T - self.multiplier_T
        stick = self._sticking()
        # (the factors from every node's step: from the sticking nodes' alone, whose set
        # changes from update to update, the ironing needed 3 times the iterations)
        steps = (step_N, step_T.ravel())
        omega_N, omega_T = ((1.0, 1.0) if self._last_step is None
                            else self._aitken(*self._last_step, steps))
        self._last_step = (steps, (omega_N, omega_T))
        s = self.elements.slave
        N[s] = np.maximum(0.0, self.multiplier_N[s] + omega_N * step_N[s])
        T[stick] = self.multiplier_T[stick] + omega_T * step_T[stick]
        self.multiplier_N, self.multiplier_T = N, T

    def _aitken(self, last: tuple, last_omegas: tuple, steps: tuple) -> tuple[float, float]:
        """Aitken's factor for each part of the Uzawa step (:meth:`augment`; collective)."""
        sums = self.comm.allreduce(np.array([(a @ (b - a), (b - a) @ (b - a))
                                             for a, b in zip(last, steps)]))
        return tuple(float(np.clip(-omega * dot / norm2, 1.0, MAX_RELAXATION))
                     if norm2 > 0.0 else 1.0 for omega, (dot, norm2) in zip(last_omegas, sums))

    def save(self) -> tuple:
        return (self.history.copy(), self.in_contact.copy(), self.closed.copy(),
                self.multiplier_N.copy(), self.multiplier_T.copy())

    def restore(self, saved: tuple) -> None:
        (self.history, self.in_contact, self.closed, self.multiplier_N,
         self.multiplier_T) = (a.copy() for a in saved)
        self._last_step = None

    def contact_state(self) -> np.ndarray:
        """(n, 2): status and master face id of every slave node on this rank ((-1, -1)
        without an element; face -1 on a rigid master)."""
        state = np.full((len(self.slaves.nodes), 2), -1, dtype=np.int64)
        el = self.elements
        if el.result is not None:
            state[el.slave, 0] = el.result.status
            state[el.slave, 1] = el.face_id
        return state

    def counts(self) -> tuple[int, int]:
        """Slave nodes in contact (closed) and in slip, on this rank."""
        r = self.elements.result
        if r is None:
            return 0, 0
        closed = r.status != OPEN
        return int(closed.sum()), int((closed & (r.status == SLIP)).sum())

    def penetration(self) -> float:
        """Largest overclosure the law acts on (the clearance plus the ramp offset of an
        initial overclosure, §3.4), on this rank, relative to the slave node's spacing."""
        r = self.elements.result
        if r is None or len(r.g_N) == 0:
            return 0.0
        return float(np.max(-(r.g_N + self._gap_offset) / self.slaves.spacing[self.elements.slave]))

    def closed_depth(self, depth: np.ndarray) -> tuple[float, float]:
        """The largest of ``depth`` (n_slaves,) over the closed slave nodes and their largest
        overclosure the law acts on (absolute), on this rank; (0, 0) with none closed."""
        r = self.elements.result
        if r is None or len(r.g_N) == 0:
            return 0.0, 0.0
        closed = r.status != OPEN
        over = -(r.g_N + self._gap_offset)[closed]
        return (float(depth[self.elements.slave[closed]].max(initial=0.0)),
                float(over.max(initial=0.0)))

    def detached(self) -> int:
        """Nodes on this rank that were closed at the last commit and project onto no
        master face even after a search in this increment: they slid off the master
        surface (meaningful after convergence, before commit)."""
        return int((self.closed & self.off_surface).sum())


def _face_size(x_faces: np.ndarray) -> np.ndarray:
    """Largest distance of a face node from the face centroid."""
    c = x_faces.mean(axis=1, keepdims=True)
    return np.linalg.norm(x_faces - c, axis=2).max(axis=1) if len(x_faces) else np.zeros(0)


def _nearest_faces(x_slaves: np.ndarray, x_faces: np.ndarray, k: int
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(slave, face) pairs: the ``k`` faces with the nearest centroids."""
    if len(x_slaves) == 0 or len(x_faces) == 0:
        return np.zeros(0, int), np.zeros(0, int)
    k = min(k, len(x_faces))
    # no distance bound: a node driven deep into the master (by a large increment or an
    # initial overlap) keeps its candidates; projection and cutoff decide on elements
    dist, face = cKDTree(x_faces.mean(axis=1)).query(x_slaves, k=k)
    slave = np.repeat(np.arange(len(x_slaves)), k)
    face, dist = face.reshape(-1), dist.reshape(-1)
    found = np.isfinite(dist)
    return slave[found], face[found]
