"""Contact surfaces of a body: slave nodes with their areas, master faces.

A facet group of a body's mesh becomes faces of a :class:`FaceType`: the
nodes of the displacement space on each facet, ordered as the face type
expects and oriented so that the surface normal points out of the body.
"""
from __future__ import annotations

from dataclasses import dataclass

import basix
import numpy as np

from dolfinx_friction import _compat as compat
from dolfinx_friction.contact.shapes import (FACE_TYPES, FaceType, revolved_area_shares,
                                             surface_vector)
from dolfinx_friction.contact.slave_weights import is_quadratic, shares
from dolfinx_friction.fem.materials import out_of_plane
from dolfinx_friction.fem.numbering import BodyField
from dolfinx_friction.fem.slave_distribution import SlaveDistribution

_FACE_TYPE = {("triangle", 1): "L2", ("triangle", 2): "L3", ("quadrilateral", 1): "L2",
              ("quadrilateral", 2): "L3", ("tetrahedron", 1): "T3", ("tetrahedron", 2): "T6",
              ("hexahedron", 1): "Q4", ("hexahedron", 2): "Q9"}
# a face type's edges as pairs of its vertices (basix's local edge order)
_FACE_EDGES = {"L3": [], "T6": [(1, 2), (0, 2), (0, 1)], "Q9": [(0, 1), (0, 2), (1, 3), (2, 3)]}


def face_type_of(field: BodyField) -> FaceType:
    cell = field.mesh.mesh.topology.cell_type.name
    degree = compat.space_degree(field.V)
    try:
        return FACE_TYPES[_FACE_TYPE[(cell, degree)]]
    except KeyError:
        raise ValueError(f"body {field.name!r}: no contact face for {cell} cells of degree "
                         f"{degree}") from None


def _closure_table(field: BodyField, face: FaceType) -> np.ndarray:
    """Cell-local dofs of every local facet of the reference cell, in face-type order."""
    cell = field.mesh.mesh.topology.cell_type.name
    topology = basix.topology(getattr(basix.CellType, cell))
    tdim = len(topology) - 1
    layout = field.V.dofmap.dof_layout
    cell_edges = [set(e) for e in topology[1]]
    table = []
    for lf, verts in enumerate(topology[tdim - 1]):
        dofs = [layout.entity_dofs(0, v)[0] for v in verts]
        if face.n_nodes > len(verts):
            if tdim == 2:  # a quadratic segment: the edge's own dof
                dofs.append(layout.entity_dofs(1, lf)[0])
            else:
                for a, b in _FACE_EDGES[face.name]:
                    edge = cell_edges.index({verts[a], verts[b]})
                    dofs.append(layout.entity_dofs(1, edge)[0])
                dofs += list(layout.entity_dofs(2, lf))  # Q9 centre node
        table.append(dofs)
    return np.array(table, dtype=np.int64)


def facet_nodes(field: BodyField, facets: np.ndarray) -> tuple[FaceType, np.ndarray]:
    """Local nodes (n_facets, nn) of exterior facets, oriented with outward normals."""
    face = face_type_of(field)
    mesh = field.mesh.mesh
    tdim = mesh.topology.dim
    cell_dofs = compat.cell_dofs(field.V)
    mesh.topology.create_connectivity(tdim - 1, tdim)
    mesh.topology.create_connectivity(tdim, tdim - 1)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    c2f = mesh.topology.connectivity(tdim, tdim - 1)
    facets = np.asarray(facets, dtype=np.int64)
    cells = f2c.array[f2c.offsets[facets]]
    width = c2f.array.size // max(len(c2f.offsets) - 1, 1)
    c2f_rows = c2f.array.reshape(-1, max(width, 1))[cells]
    local_facet = np.argmax(c2f_rows == facets[:, None], axis=1)
    nodes = cell_dofs[cells[:, None], _closure_table(field, face)[local_facet]]
    # orient: the normal at the face centre must point away from the cell centre
    X = field.X
    _, dphi, _ = face.evaluate(face.centroid[None])
    m = surface_vector(np.einsum("ka,fkd->fad", dphi[0], X[nodes]))
    outward = X[nodes].mean(axis=1) - X[cell_dofs[cells]].mean(axis=1)
    flip = np.einsum("fd,fd->f", m, outward) < 0.0
    nodes[flip] = nodes[flip][:, list(face.flip)]
    return face, nodes


class SlaveNodes:
    """The owned slave nodes of a contact pair on this rank, with their areas ``A_p``.

    ``A_p = sum_f w_p,f A_f`` over the slave faces around the node
    (docs/theory.md §2.1; with ``subfaces``, on quadratic faces, the node's share of their
    linear sub-faces), thickness included in 2D; on an axisymmetric body the share
    ``int N_p 2 pi r ds`` of the revolved faces (per full revolution; a node on the axis
    gets the share of its faces too; no sub-faces).  :meth:`update_areas` recomputes it on
    the deformed faces (collective), and with it, with ``subfaces`` on quadratic faces,
    :attr:`distribution`: where each node's contact force acts (otherwise None: on the
    node).
    """

    def __init__(self, field: BodyField, group: str, subfaces: bool = False):
        self.field = field
        self.face, self._facet_nodes = facet_nodes(field, field.mesh.groups[group][1])
        marks = np.ones((self._facet_nodes.size, field.gdim))
        owned = np.flatnonzero(field.to_owners(self._facet_nodes.ravel(), marks)[:, 0] > 0)
        self.local = owned  # local node indices in the slave body
        self.nodes = field.nodes[owned]  # system node indices
        self.X = field.X[owned]  # (n, gdim) reference coordinates
        self._subfaces = subfaces and is_quadratic(self.face) and not field.axisymmetric
        self.distribution = (SlaveDistribution(field, self.face, self._facet_nodes, self.nodes)
                             if self._subfaces else None)
        #: (n,) the areas on the undeformed faces
        self.reference_area = self._areas(field.X)
        self.update_areas()

    @property
    def facet_nodes(self) -> np.ndarray:
        """(n_faces, nn) local nodes of the slave faces this rank holds (read-only)."""
        nodes = self._facet_nodes.view()
        nodes.flags.writeable = False
        return nodes

    def update_areas(self) -> None:
        """``A_p`` on the faces as deformed by the body's current displacement."""
        f = self.field
        x = f.X + f.u.x.array.reshape(-1, f.gdim)[: len(f.X)]
        self.area = self._areas(x)
        if self.distribution is not None:
            self.distribution.update(x)
        #: nodal spacing: the side of the representative area (its length in 2D: the
        #: meridian length of an axisymmetric body's)
        if f.axisymmetric:
            self.spacing = self._areas(x, revolved=False)
        else:
            thickness = out_of_plane(f.thickness, f.gdim)
            self.spacing = self.area / thickness if f.gdim == 2 else np.sqrt(self.area)

    def _areas(self, x: np.ndarray, revolved: bool = True) -> np.ndarray:
        """The owned slave nodes' representative areas (n,) with the body's nodes at ``x``
        (local nodes, gdim) [length^2; in 2D length x thickness, or the revolved area of an
        axisymmetric body; not ``revolved``: its length]."""
        f = self.field
        coords = x[self._facet_nodes]
        if f.axisymmetric and revolved:
            area_shares = revolved_area_shares(self.face, coords)
        else:
            thickness = 1.0 if f.axisymmetric else out_of_plane(f.thickness, f.gdim)
            area_shares = shares(self.face, coords, thickness, self._subfaces)
        share = np.zeros((self._facet_nodes.size, f.gdim))
        share[:, 0] = area_shares.ravel()
        return f.to_owners(self._facet_nodes.ravel(), share)[self.local, 0]


@dataclass
class MasterFaces:
    """The master faces of a contact pair held by this rank (its own facets)."""

    face: FaceType
    local: np.ndarray  # (n_faces, nn) local node indices in the master body
    ids: np.ndarray  # (n_faces,) global face numbers, unique over all ranks
    nodes: np.ndarray  # (n_faces, nn) system node indices
    X: np.ndarray  # (n_faces, nn, gdim) reference coordinates


def master_faces(field: BodyField, group: str) -> MasterFaces:
    _, facets = field.mesh.groups[group]
    face, nodes = facet_nodes(field, facets)
    comm = field.V.mesh.comm
    first = comm.scan(len(nodes)) - len(nodes)
    ids = first + np.arange(len(nodes), dtype=np.int64)
    return MasterFaces(face, nodes, ids, field.nodes[nodes], field.X[nodes])
