"""Displacement fields of the bodies and the system numbering that joins them.

Each deformable body has its own mesh and vector Lagrange space (a *block*).
Every force-controlled or displacement-driven rigid obstacle adds one node of
``gdim`` dofs (its translation), owned by rank 0.  The system numbers nodes
rank by rank: on each rank its owned nodes of body 0, body 1, ..., then the
rigid nodes; the scalar dof of node ``N``, component ``c`` is ``N*gdim + c``.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Optional

import numpy as np
from mpi4py import MPI

from dolfinx_friction import _compat as compat
from dolfinx_friction.fem.tagged_mesh import BodyMesh


class DofLayout:
    """System node numbering over the blocks of all bodies plus the rigid nodes."""

    def __init__(self, comm: MPI.Comm, index_maps: list, n_rigid: int):
        self.comm = comm
        owned = [im.size_local for im in index_maps] + [n_rigid if comm.rank == 0 else 0]
        self.block_offsets = np.concatenate([[0], np.cumsum(owned)]).astype(np.int64)
        self.n_owned = int(self.block_offsets[-1])
        ends = np.cumsum(comm.allgather(self.n_owned))
        self.start = int(ends[comm.rank] - self.n_owned)
        self.n_global = int(ends[-1])
        # what every rank needs to number the ghosts of every block
        table = comm.allgather((self.start, self.block_offsets[:-1].tolist(),
                                [im.local_range[0] for im in index_maps]))
        self._starts = np.array([t[0] for t in table], dtype=np.int64)
        self._offsets = np.array([t[1] for t in table], dtype=np.int64)
        self._ranges = np.array([t[2] for t in table], dtype=np.int64).reshape(comm.size, -1)
        self._nodes = []
        for b, im in enumerate(index_maps):
            own = self.start + self.block_offsets[b] + np.arange(im.size_local, dtype=np.int64)
            ghosts = np.asarray(im.ghosts, dtype=np.int64)
            self._nodes.append(np.concatenate([own, self.from_block_global(b, ghosts)]))
        self._rigid_start = int(self._starts[0] + self._offsets[0, -1]) if n_rigid else -1

    def from_block_global(self, block: int, nodes: np.ndarray) -> np.ndarray:
        """System node index of nodes given by their global index in a body's own numbering."""
        owner = np.searchsorted(self._ranges[:, block], nodes, side="right") - 1
        return (self._starts[owner] + self._offsets[owner, block]
                + (nodes - self._ranges[owner, block]))

    def nodes(self, block: int) -> np.ndarray:
        """System node index of every local node (owned, then ghost) of a body block."""
        return self._nodes[block]

    def rigid_node(self, k: int) -> int:
        """System node index of the k-th rigid obstacle (owned by rank 0)."""
        return self._rigid_start + k

    def owned_slice(self, block: int, gdim: int) -> slice:
        """Slice of a block's owned dofs in the rank's local part of a system vector."""
        return slice(int(self.block_offsets[block]) * gdim,
                     int(self.block_offsets[block + 1]) * gdim)


@dataclass
class BodyField:
    """A deformable body: its mesh, function space, displacement and system numbering;
    ``thickness`` is the out-of-plane thickness of a 2D body (scales its areas), and an
    ``axisymmetric`` 2D body is a meridian section (:mod:`~dolfinx_friction.fem.axisymmetric`:
    its areas are those of the revolved surfaces, its thickness is not used)."""

    name: str
    thickness: float
    mesh: BodyMesh
    V: object  # dolfinx FunctionSpace (vector Lagrange)
    u: object  # dolfinx Function
    block: int
    nodes: np.ndarray  # system node index per local node
    X: np.ndarray  # (n_local_nodes, gdim) reference coordinates per local node
    axisymmetric: bool = field(default=False, kw_only=True)

    @property
    def gdim(self) -> int:
        return self.X.shape[1]

    @property
    def n_owned(self) -> int:
        return self.V.dofmap.index_map.size_local

    def local_group_nodes(self, name: str) -> np.ndarray:
        """Local nodes (owned and ghost) on the entities of a named group."""
        dim, entities = self.mesh.groups[name]
        return compat.locate_nodes(self.V, dim, entities)

    def to_owners(self, local_nodes: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Sum per-node values (n, gdim) given at local nodes onto their owners' nodes."""
        f = compat.function(self.V)
        f.x.array[:] = 0.0
        np.add.at(f.x.array.reshape(-1, self.gdim), local_nodes, values)
        compat.scatter_reverse_add(f)
        return f.x.array.reshape(-1, self.gdim)[: self.n_owned].copy()

    def owned_group_nodes(self, name: str) -> np.ndarray:
        """Owned nodes on a named group, known to their owner even where the group's
        entities lie on another rank."""
        local = self.local_group_nodes(name)
        marks = self.to_owners(local, np.ones((len(local), self.gdim)))
        return np.flatnonzero(marks[:, 0] > 0)


def make_fields(comm: MPI.Comm, meshes: Sequence[BodyMesh], n_rigid: int,
                degrees: Optional[Sequence[Optional[int]]] = None,
                thicknesses: Optional[Sequence[float]] = None,
                axisymmetric: Optional[Sequence[bool]] = None
                ) -> tuple[list[BodyField], DofLayout]:
    """Function spaces for all bodies and the system numbering joining them: body ``k``
    (named ``meshes[k].name``) of degree ``degrees[k]`` (None, the default: the geometry
    degree of its mesh), thickness ``thicknesses[k]`` (default 1) and axisymmetric if
    ``axisymmetric[k]`` (default: no)."""
    degrees = list(degrees) if degrees is not None else [None] * len(meshes)
    thicknesses = list(thicknesses) if thicknesses is not None else [1.0] * len(meshes)
    axisymmetric = list(axisymmetric) if axisymmetric is not None else [False] * len(meshes)
    spaces = []
    for bm, degree in zip(meshes, degrees):
        spaces.append(compat.vector_space(bm.mesh, degree or compat.geometry_degree(bm.mesh)))
    layout = DofLayout(comm, [V.dofmap.index_map for V in spaces], n_rigid)
    fields = []
    for b, (bm, V, thickness) in enumerate(zip(meshes, spaces, thicknesses)):
        gdim = bm.mesh.geometry.dim
        X = V.tabulate_dof_coordinates()[:, :gdim].copy()
        fields.append(BodyField(bm.name, float(thickness), bm, V, compat.function(V), b,
                                layout.nodes(b), X, axisymmetric=bool(axisymmetric[b])))
    return fields, layout
