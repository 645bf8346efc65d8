"""Quadratic slave faces on a mesh of first-order geometry: how deep their mid-side nodes
lie inside the curved surface (:mod:`~dolfinx_friction.contact.faceting`, theory §2.1)."""
from __future__ import annotations

from typing import Optional

import numpy as np

from dolfinx_friction import _compat as compat
from dolfinx_friction.contact.faceting import EDGES, chord_depths, vertex_count
from dolfinx_friction.contact.shapes import FaceType, surface_vector
from dolfinx_friction.contact.slave_weights import is_quadratic
from dolfinx_friction.fem.numbering import BodyField


def mid_side_depths(field: BodyField, face: FaceType, facet_nodes: np.ndarray,
                    local: np.ndarray) -> Optional[np.ndarray]:
    """(n,) chord depth [length] at the slave nodes ``local`` (local node indices, owned):
    at a mid-side node the sagitta of its edge, 0 at vertex and centre nodes; None unless
    the faces are quadratic on a mesh of first-order geometry (collective).

    ``facet_nodes`` (n_faces, nn): the local nodes of the slave faces this rank holds, each
    face on one rank, outward.  The vertex normals sum the faces' surface vectors over all
    ranks, so the depths are those of a serial run to round-off."""
    if not is_quadratic(face) or compat.geometry_degree(field.V.mesh) != 1:
        return None
    gdim, nv = field.gdim, vertex_count(face)
    x = field.X[facet_nodes]
    _, dphi, _ = face.evaluate(face.nodes[:nv])
    tangents = np.einsum("vka,fkd->fvad", dphi, x).reshape(-1, face.fdim, gdim)
    m = surface_vector(tangents)
    normals = compat.function(field.V)
    normals.x.array[:] = 0.0
    normals.x.array[: field.n_owned * gdim] = field.to_owners(
        facet_nodes[:, :nv].ravel(), m).ravel()
    compat.scatter_forward(normals)
    n = normals.x.array.reshape(-1, gdim)[facet_nodes[:, :nv]]
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    depth = chord_depths(face, x, n)  # (n_faces, n_edges)
    mids = facet_nodes[:, [m for _, _, m in EDGES[face.name]]].ravel()
    # a mid-side node is on the edge of one or two faces: their mean (the same value)
    sums = np.zeros((mids.size, gdim))
    sums[:, 0], sums[:, 1] = depth.ravel(), 1.0
    owned = field.to_owners(mids, sums)[local]
    return np.where(owned[:, 1] > 0, owned[:, 0] / np.maximum(owned[:, 1], 1.0), 0.0)
