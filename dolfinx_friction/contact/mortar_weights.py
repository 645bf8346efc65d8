"""Mortar integrals of linear slave faces against master faces (docs/theory.md §2.4).

For a slave face ``S`` and a master face ``M`` the integrals

    I_ab = int_{S ∩ M'} N_a(s) N_b(eta(s)) ds        (a: nodes of S, b: nodes of M)

over the part of ``S`` that ``M`` covers, ``M'`` being ``M`` projected onto the plane
(line in 2D) of ``S`` along the slave normal, and ``eta(s)`` the closest-point projection
of the slave point ``s`` onto ``M``.  Summed over the master faces, ``sum_b I_ab`` is the
share ``int N_a ds`` of the slave node (partition of unity).  The overlap is found by
segmentation: in 2D the slave segment is cut at the projections of the master nodes, in
3D the projected master polygon is clipped against the slave polygon
(Sutherland-Hodgman, both convex) and the clipped polygon cut into a fan of triangles.
Master faces may be quadratic (L3, T6, Q9: their polygon is that of their corners, so
their edges are taken straight); quadratic slave faces enter as their linear sub-faces
(:data:`~dolfinx_friction.contact.slave_weights.SUBFACES`).  Gauss rules exact for the
products on a flat interface: 2 points per segment piece (up to cubics), the 6-point
degree-4 triangle rule against linear masters (bilinear x bilinear on parallelograms), a
collapsed 4 x 4 Gauss rule (degree 6) against quadratic ones.  Pure numpy, batched over
(slave face, master face) pairs.
"""
from __future__ import annotations

import numpy as np

from dolfinx_friction.contact.projection import project
from dolfinx_friction.contact.shapes import (Array, FaceType, collapsed_triangle_rule,
                                             gauss_line, surface_vector, triangle_rule)

#: the linear face types
LINEAR_FACES = ("L2", "T3", "Q4")
#: the slave face types the integrals are defined for: linear, and straight L3 segments
SLAVE_FACES = LINEAR_FACES + ("L3",)
# a face's corners in cyclic order (counter-clockwise about its surface vector)
_CYCLE = {"T3": [0, 1, 2], "T6": [0, 1, 2], "Q4": [0, 1, 3, 2], "Q9": [0, 1, 3, 2]}


def mortar_integrals(slave: FaceType, x_slave: Array, master: FaceType,
                     x_master: Array, revolved: bool = False) -> Array:
    """The integrals ``I_ab`` (n, nn_s, nn_m) [length in 2D (per unit thickness),
    area in 3D; ``revolved``: of the surfaces the 2D segments sweep about the axis
    ``x[..., 0] = 0``, weight ``2 pi r``] of the pairs of slave faces with node coordinates
    ``x_slave`` (n, nn_s, gdim) and master faces ``x_master`` (n, nn_m, gdim), row by row;
    0 where they do not overlap."""
    if slave.name not in SLAVE_FACES:
        raise ValueError(f"mortar integrals need linear slave faces, not {slave.name}")
    n = len(x_slave)
    out = np.zeros((n, slave.n_nodes, master.n_nodes))
    if n == 0:
        return out
    if slave.fdim == 1:
        pair, x, xi_s, w = _segment_points(x_slave, x_master)
    else:
        pair, x, xi_s, w = _polygon_points(slave, x_slave, master, x_master)
    if len(pair) == 0:
        return out
    if revolved:
        w = 2.0 * np.pi * x[:, 0] * w
    N_s = slave.evaluate(xi_s)[0]
    N_m = master.evaluate(project(master, x, x_master[pair]).xi)[0]
    np.add.at(out, pair, w[:, None, None] * N_s[:, :, None] * N_m[:, None, :])
    return out


def _segment_points(x_slave: Array, x_master: Array
                    ) -> tuple[np.ndarray, Array, Array, Array]:
    """2D: quadrature points of the overlaps of slave segments (n, 2, 2) with master
    segments (n, 2, 2): pair index (q,), point (q, 2), slave coordinate (q, 1), weight (q,)."""
    x0, x1 = x_slave[:, 0], x_slave[:, 1]
    length = np.linalg.norm(x1 - x0, axis=1)
    t = (x1 - x0) / length[:, None]
    # the master nodes' projections onto the slave segment, in its coordinate [-1, 1]
    xi_m = 2.0 * np.einsum("nkd,nd->nk", x_master - x0[:, None], t) / length[:, None] - 1.0
    lo, hi = np.maximum(xi_m.min(axis=1), -1.0), np.minimum(xi_m.max(axis=1), 1.0)
    pair = np.flatnonzero(hi > lo)
    p, w = gauss_line(2)
    half = 0.5 * (hi[pair] - lo[pair])
    xi = (0.5 * (hi[pair] + lo[pair]))[:, None] + half[:, None] * p[None, :, 0]  # (m, 2)
    weight = (half * 0.5 * length[pair])[:, None] * w[None, :]
    x = x0[pair, None] + 0.5 * (xi + 1.0)[..., None] * (x1 - x0)[pair, None]
    return np.repeat(pair, len(w)), x.reshape(-1, 2), xi.reshape(-1, 1), weight.ravel()


def _polygon_points(slave: FaceType, x_slave: Array, master: FaceType, x_master: Array
                    ) -> tuple[np.ndarray, Array, Array, Array]:
    """3D: quadrature points of the overlaps of slave faces (n, nn_s, 3) with master faces
    (n, nn_m, 3) projected onto the slave face's plane: pair index (q,), point (q, 3),
    slave parametric coordinates (q, 2), weight (q,)."""
    n = len(x_slave)
    c = x_slave.mean(axis=1)
    _, dphi, _ = slave.evaluate(slave.centroid[None])
    normal = surface_vector(np.einsum("ka,nkd->nad", dphi[0], x_slave))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    e1 = x_slave[:, 1] - x_slave[:, 0]
    e1 -= np.einsum("nd,nd->n", e1, normal)[:, None] * normal
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    frame = np.stack([e1, np.cross(normal, e1)], axis=1)  # (n, 2, 3)

    def plane(x: Array) -> Array:
        return np.einsum("nkd,nad->nka", x - c[:, None], frame)

    clip = plane(x_slave[:, _CYCLE[slave.name]])  # counter-clockwise, convex
    corners = len(_CYCLE[master.name])
    poly = plane(x_master[:, _CYCLE[master.name]])
    reverse = _signed_area(poly, np.full(n, corners)) < 0.0  # the master faces the slave
    poly[reverse] = poly[reverse, ::-1]
    count = np.full(n, corners)
    for j in range(clip.shape[1]):
        poly, count = _clip(poly, count, clip[:, j], clip[:, (j + 1) % clip.shape[1]])
    # a fan of triangles (v0, v_i, v_i+1) and a rule of degree 4 (6) on each
    pts, wts = triangle_rule() if master.name in LINEAR_FACES else collapsed_triangle_rule(4)
    i = np.arange(1, max(poly.shape[1] - 1, 1))
    tri, fan = np.nonzero(i[None, :] + 1 < count[:, None])
    fan = i[fan]
    v0 = poly[tri, 0]
    a, b = poly[tri, fan] - v0, poly[tri, fan + 1] - v0
    area2 = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]  # twice the area
    y = v0[:, None] + pts[None, :, :1] * a[:, None] + pts[None, :, 1:] * b[:, None]
    weight = (area2[:, None] * wts[None, :]).ravel()
    pair = np.repeat(tri, len(wts))
    x = c[pair] + np.einsum("qa,qad->qd", y.reshape(-1, 2), frame[pair])
    xi_s = project(slave, x, x_slave[pair]).xi
    return pair, x, xi_s, weight


def _signed_area(poly: Array, count: np.ndarray) -> Array:
    """Signed areas (n,) of polygons (n, V, 2) with ``count`` (n,) vertices (shoelace)."""
    nxt = _next(poly, count)
    valid = np.arange(poly.shape[1])[None] < count[:, None]
    cross = poly[..., 0] * nxt[..., 1] - poly[..., 1] * nxt[..., 0]
    return 0.5 * np.where(valid, cross, 0.0).sum(axis=1)


def _next(poly: Array, count: np.ndarray) -> Array:
    """Each polygon's vertices shifted by one: vertex i+1 (vertex 0 after the last)."""
    i = np.arange(poly.shape[1])[None]
    following = np.where(i + 1 < count[:, None], i + 1, 0)
    return np.take_along_axis(poly, following[..., None], axis=1)


def _clip(poly: Array, count: np.ndarray, a: Array, b: Array) -> tuple[Array, np.ndarray]:
    """One Sutherland-Hodgman step: the polygons (n, V, 2) with ``count`` vertices cut to
    the left of the lines from ``a`` to ``b`` (n, 2); returns the polygons and counts."""
    n, V, _ = poly.shape
    q = _next(poly, count)
    edge = b - a

    def side(p: Array) -> Array:
        return edge[:, None, 0] * (p[..., 1] - a[:, None, 1]) - \
            edge[:, None, 1] * (p[..., 0] - a[:, None, 0])

    sp, sq = side(poly), side(q)
    inside_p, inside_q = sp >= 0.0, sq >= 0.0
    denominator = np.where(sp == sq, 1.0, sp - sq)
    crossing = poly + (sp / denominator)[..., None] * (q - poly)
    valid = np.arange(V)[None] < count[:, None]
    keep = (np.stack([inside_p, inside_p != inside_q], axis=2) & valid[..., None]).reshape(n, 2 * V)
    out = np.stack([poly, crossing], axis=2).reshape(n, 2 * V, 2)
    order = np.argsort(~keep, axis=1, kind="stable")
    count = keep.sum(axis=1)
    width = max(int(count.max(initial=0)), 1)
    return np.take_along_axis(out, order[:, :width, None], axis=1), count
