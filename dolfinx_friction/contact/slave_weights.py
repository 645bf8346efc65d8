"""Slave nodal areas and where a slave node's force goes on quadratic faces (docs/theory.md §2.1).

Linear faces (L2, T3, Q4) keep CalculiX's lumped shares: node ``k`` of face ``f`` holds
``w_k A_f`` and its contact force acts on node ``k`` alone; so do quadratic faces that
touch a deformable master with the nodal distribution (the master would receive node
``k``'s force at one point, which breaks the patch test: docs/theory.md §2.1; the mortar
distribution hands it over consistently, §2.4).

A quadratic face (L3, T6, Q9) is split into linear sub-faces (:data:`SUBFACES`: 2
segments, 4 triangles, 4 quadrilaterals through its mid-side and centre nodes).  Node
``k``'s area is its share of them, ``A_k = int L_k dA`` with ``L_k`` the sub-faces'
linear shape function of node ``k`` (positive everywhere: 1/4 and 1/2 of a segment for end
and middle nodes; 1/12 and 1/4 of a T6 face for corners and mid-sides; 1/16, 1/8, 1/4 of a
Q9 face for corners, mid-sides and centre).  The nodal pressures ``p_k``, interpolated
linearly over the sub-faces, ``p(x) = sum_k L_k(x) p_k``, load the face's nodes as the
face's own shape functions ``N_i`` demand:

    f_i = int N_i p dA = sum_k C_ik p_k,    C_ik = int N_i L_k dA,    sum_i C_ik = A_k,

so a uniform pressure gives the consistent nodal forces of the quadratic face (zero at T6
corners) and no vertex/mid-side zig-zag.  Node ``k``'s force ``F_k = A_k p_k`` goes to node
``i`` with the weight ``T_ik = C_ik / A_k`` (``sum_i T_ik = 1``).  Pure numpy, no dolfinx.
"""
from __future__ import annotations

from functools import cache

import numpy as np

from dolfinx_friction.contact.shapes import FACE_TYPES, Array, FaceType, face_areas, surface_vector

#: linear sub-faces of each quadratic face type: the sub-face type and its nodes, as local
#: nodes of the face (in the sub-face type's node order; shapes.py's numbering)
SUBFACES: dict[str, tuple[str, tuple[tuple[int, ...], ...]]] = {
    "L3": ("L2", ((0, 2), (2, 1))),
    "T6": ("T3", ((0, 5, 4), (5, 1, 3), (4, 3, 2), (3, 4, 5))),
    "Q9": ("Q4", ((0, 4, 5, 8), (4, 1, 8, 6), (5, 8, 2, 7), (8, 6, 7, 3))),
}


def is_quadratic(face: FaceType) -> bool:
    """Whether slave forces on faces of this type are spread over the face (quadratic)."""
    return face.name in SUBFACES


@cache
def _rule(name: str) -> tuple[Array, Array, Array, Array]:
    """Quadrature over the sub-faces of face type ``name`` in the face's parametric
    coordinates: points (n_q, fdim), weights (n_q,) (parametric measure), the face's shape
    functions ``N`` (n_q, nn) and the sub-faces' ``L`` (n_q, nn) at the points."""
    face = FACE_TYPES[name]
    sub_name, subs = SUBFACES[name]
    sub = FACE_TYPES[sub_name]
    pts, wts = sub.quadrature
    L_sub, dL_sub, _ = sub.evaluate(pts)
    points, weights, L = [], [], []
    for nodes in subs:
        corners = face.nodes[list(nodes)]  # (nn_sub, fdim) parametric
        jac = np.einsum("ka,kb->ab", dL_sub[0], corners)  # affine map: constant Jacobian
        points.append(L_sub @ corners)
        weights.append(wts * abs(np.linalg.det(jac.T)))
        full = np.zeros((len(pts), face.n_nodes))
        full[:, list(nodes)] = L_sub
        L.append(full)
    points, weights, L = np.concatenate(points), np.concatenate(weights), np.concatenate(L)
    N, _, _ = face.evaluate(points)
    return points, weights, N, L


def distribution(face: FaceType, coords: Array) -> Array:
    """``C[f, i, k] = int_f N_i L_k dA`` (n_faces, nn, nn) of faces with node coordinates
    ``coords`` (n_faces, nn, gdim) [area; length in 2D]; quadratic face types only."""
    points, weights, N, L = _rule(face.name)
    _, dphi, _ = face.evaluate(points)
    tangents = np.einsum("qka,fkd->fqad", dphi, coords)
    n_f, n_q = tangents.shape[:2]
    m = surface_vector(tangents.reshape(n_f * n_q, face.fdim, coords.shape[-1]))
    density = np.linalg.norm(m, axis=-1).reshape(n_f, n_q) * weights
    return np.einsum("fq,qi,qk->fik", density, N, L)


def shares(face: FaceType, coords: Array, thickness: float = 1.0,
           subfaces: bool = True) -> Array:
    """Each node's share of its face's area (n_faces, nn) for faces with node coordinates
    ``coords`` (n_faces, nn, gdim), times ``thickness`` (2D): ``int_f L_k dA`` on
    quadratic faces with ``subfaces`` (the column sums of :func:`distribution`), else
    ``w_k A_f`` (the face type's ``area_weights``); a node's area ``A_k`` is the sum of
    its shares over its faces [area; in 2D length x thickness]."""
    if subfaces and is_quadratic(face):
        return thickness * distribution(face, coords).sum(axis=1)
    areas = thickness * face_areas(face, coords)
    return areas[:, None] * np.asarray(face.area_weights)[None, :]
