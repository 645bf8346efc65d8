"""How far the mid-side nodes of quadratic faces on first-order geometry lie off the surface
(docs/theory.md §2.1).

A mesh of first-order geometry puts the mid-side nodes of a curved surface on the chords
of its facets: ``h^2 / 8R`` inside the surface (``R``: its radius of curvature), so the
vertex nodes stand proud and carry more of the contact pressure.  The depth is estimated
per face edge from the surface normals ``n_a``, ``n_b`` at the edge's end vertices, the
sagitta of an arc with those normals,

    s = (n_b - n_a) . (x_b - x_a) / 8        (= h^2 / 8R on a circle of radius R).

Edges whose end normals differ by more than :data:`FEATURE` (about 29 degrees) are edges of
the geometry (a corner or a crease), not facets of a curved surface: depth 0.  Pure numpy.
"""
from __future__ import annotations

import numpy as np

from dolfinx_friction.contact.shapes import Array, FaceType

#: the edges of each quadratic face type: (end vertex, end vertex, mid-side node), local
#: nodes of the face in the order of shapes.py (T6: mid-sides of 12, 02, 01; Q9: of 01, 02,
#: 13, 23, then the centre)
EDGES: dict[str, tuple[tuple[int, int, int], ...]] = {
    "L3": ((0, 1, 2),),
    "T6": ((1, 2, 3), (0, 2, 4), (0, 1, 5)),
    "Q9": ((0, 1, 4), (0, 2, 5), (1, 3, 6), (2, 3, 7)),
}
#: largest |n_b - n_a| (unit normals) of an edge on a smooth surface: 0.5 is 29 degrees
FEATURE = 0.5


def vertex_count(face: FaceType) -> int:
    """Number of corner vertices of a quadratic face type (2, 3 or 4)."""
    return {"L3": 2, "T6": 3, "Q9": 4}[face.name]


def chord_depths(face: FaceType, x: Array, normals: Array) -> Array:
    """(n_faces, n_edges) sagitta ``s`` of each edge of EDGES[face.name] [length], from the
    face node coordinates ``x`` (n_faces, nn, gdim) and the unit surface normals at the
    face's vertices ``normals`` (n_faces, n_vertices, gdim); 0 on feature edges."""
    depths = np.zeros((len(x), len(EDGES[face.name])))
    for e, (a, b, _) in enumerate(EDGES[face.name]):
        dn = normals[:, b] - normals[:, a]
        s = np.abs(np.einsum("fd,fd->f", dn, x[:, b] - x[:, a])) / 8.0
        depths[:, e] = np.where(np.linalg.norm(dn, axis=1) > FEATURE, 0.0, s)
    return depths
