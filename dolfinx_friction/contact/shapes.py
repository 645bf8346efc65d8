"""Master-face shape functions: L2, L3 (2D segments), T3, T6, Q4, Q9 (3D faces).

Node order follows basix's reference cells, so dolfinx facet dofs map onto it
by a fixed table: vertices first (quadrilaterals in tensor order
``(-1,-1), (1,-1), (-1,1), (1,1)``), then one node per edge in basix's
local edge order, then the face interior node.

Parametric domains (docs/theory.md §3.1, §9): segments and quadrilaterals
use ``[-1, 1]`` per coordinate, triangles the unit triangle.  The surface
Jacobian vector ``m = q_,xi x q_,eta`` (3D) or ``m = R q_,xi`` (2D) then points
out of the master body when the face is oriented as its owning cell demands
(:data:`FLIP` reorders a face that is not).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@dataclass(frozen=True)
class FaceType:
    """A master-face type: its reference nodes, domain, flip and area weights."""

    name: str
    fdim: int  # parametric dimension (1 for segments, 2 for faces)
    nodes: Array  # (n_nodes, fdim) reference coordinates
    simplex: bool
    flip: tuple[int, ...]  # node permutation that reverses the orientation
    area_weights: tuple[float, ...]  # nodal share of the face area (sums to 1)
    quadrature: tuple[Array, Array]  # points (n_q, fdim), weights (n_q,)

    @property
    def n_nodes(self) -> int:
        return len(self.nodes)

    @property
    def centroid(self) -> Array:
        return np.full(self.fdim, 1.0 / 3.0) if self.simplex else np.zeros(self.fdim)

    def evaluate(self, xi: Array) -> tuple[Array, Array, Array]:
        """Shape functions and their first and second derivatives.

        ``xi`` has shape (n, fdim); returns ``phi`` (n, nn), ``dphi`` (n, nn, fdim)
        and ``d2phi`` (n, nn, fdim, fdim).
        """
        return _EVALUATORS[self.name](np.asarray(xi, dtype=float))

    def distance_outside(self, xi: Array) -> Array:
        """How far (in parametric units) each point of ``xi`` (n, fdim) lies outside the domain."""
        if self.simplex:
            parts = [-xi[:, 0], -xi[:, 1], xi[:, 0] + xi[:, 1] - 1.0]
        else:
            parts = [np.abs(xi[:, a]) - 1.0 for a in range(self.fdim)]
        return np.maximum(np.max(parts, axis=0), 0.0)

    def clamp(self, xi: Array) -> Array:
        """Closest point of the parametric domain (Euclidean, in parametric space)."""
        if not self.simplex:
            return np.clip(xi, -1.0, 1.0)
        out = np.clip(xi, 0.0, None)
        excess = out.sum(axis=1) - 1.0
        over = excess > 0.0
        # project onto the hypotenuse, then back into [0, 1]
        out[over] -= 0.5 * excess[over, None]
        return np.clip(out, 0.0, 1.0)


def _line_quadratic(x: Array) -> tuple[Array, Array, Array]:
    """1D quadratic Lagrange basis on nodes (-1, 1, 0): values, first, second derivatives."""
    one = np.ones_like(x)
    v = np.stack([0.5 * x * (x - 1.0), 0.5 * x * (x + 1.0), 1.0 - x * x], axis=-1)
    d = np.stack([x - 0.5, x + 0.5, -2.0 * x], axis=-1)
    dd = np.stack([one, one, -2.0 * one], axis=-1)
    return v, d, dd


def _line_linear(x: Array) -> tuple[Array, Array, Array]:
    v = np.stack([0.5 * (1.0 - x), 0.5 * (1.0 + x)], axis=-1)
    d = np.broadcast_to(np.array([-0.5, 0.5]), v.shape).copy()
    return v, d, np.zeros_like(v)


def _eval_L2(xi: Array):
    v, d, dd = _line_linear(xi[:, 0])
    return v, d[..., None], dd[..., None, None]


def _eval_L3(xi: Array):
    v, d, dd = _line_quadratic(xi[:, 0])
    return v, d[..., None], dd[..., None, None]


def _tensor(basis, xi: Array, order: list[tuple[int, int]]):
    """Tensor-product basis on [-1,1]^2 from a 1D basis; ``order`` lists (i, j) per node."""
    vx, dx, ddx = basis(xi[:, 0])
    vy, dy, ddy = basis(xi[:, 1])
    i = np.array([o[0] for o in order])
    j = np.array([o[1] for o in order])
    phi = vx[:, i] * vy[:, j]
    dphi = np.stack([dx[:, i] * vy[:, j], vx[:, i] * dy[:, j]], axis=-1)
    d2 = np.empty(phi.shape + (2, 2))
    d2[..., 0, 0] = ddx[:, i] * vy[:, j]
    d2[..., 1, 1] = vx[:, i] * ddy[:, j]
    d2[..., 0, 1] = d2[..., 1, 0] = dx[:, i] * dy[:, j]
    return phi, dphi, d2


# 1D node indices: linear (-1, 1) -> (0, 1); quadratic (-1, 1, 0) -> (0, 1, 2)
_Q4_ORDER = [(0, 0), (1, 0), (0, 1), (1, 1)]
# vertices, edges (0,1), (0,2), (1,3), (2,3), interior
_Q9_ORDER = _Q4_ORDER + [(2, 0), (0, 2), (1, 2), (2, 1), (2, 2)]


def _eval_Q4(xi: Array):
    return _tensor(_line_linear, xi, _Q4_ORDER)


def _eval_Q9(xi: Array):
    return _tensor(_line_quadratic, xi, _Q9_ORDER)


def _eval_T3(xi: Array):
    x, y = xi[:, 0], xi[:, 1]
    n = len(x)
    phi = np.stack([1.0 - x - y, x, y], axis=-1)
    dphi = np.broadcast_to(np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]]), (n, 3, 2)).copy()
    return phi, dphi, np.zeros((n, 3, 2, 2))


def _eval_T6(xi: Array):
    x, y = xi[:, 0], xi[:, 1]
    n = len(x)
    z = 1.0 - x - y
    # vertices 0 (0,0), 1 (1,0), 2 (0,1); edges (1,2), (0,2), (0,1)
    phi = np.stack(
        [z * (2 * z - 1), x * (2 * x - 1), y * (2 * y - 1), 4 * x * y, 4 * y * z, 4 * x * z],
        axis=-1,
    )
    dphi = np.empty((n, 6, 2))
    dphi[:, 0, 0] = dphi[:, 0, 1] = 1.0 - 4.0 * z
    dphi[:, 1] = np.stack([4 * x - 1, 0 * x], axis=-1)
    dphi[:, 2] = np.stack([0 * y, 4 * y - 1], axis=-1)
    dphi[:, 3] = np.stack([4 * y, 4 * x], axis=-1)
    dphi[:, 4] = np.stack([-4 * y, 4 * (z - y)], axis=-1)
    dphi[:, 5] = np.stack([4 * (z - x), -4 * x], axis=-1)
    hess = np.array(
        [
            [[4, 4], [4, 4]],
            [[4, 0], [0, 0]],
            [[0, 0], [0, 4]],
            [[0, 4], [4, 0]],
            [[0, -4], [-4, -8]],
            [[-8, -4], [-4, 0]],
        ],
        dtype=float,
    )
    return phi, dphi, np.broadcast_to(hess, (n, 6, 2, 2)).copy()


_EVALUATORS = {"L2": _eval_L2, "L3": _eval_L3, "T3": _eval_T3, "T6": _eval_T6,
               "Q4": _eval_Q4, "Q9": _eval_Q9}


def gauss_line(n: int) -> tuple[Array, Array]:
    p, w = np.polynomial.legendre.leggauss(n)
    return p[:, None], w


def _gauss_quad(n: int) -> tuple[Array, Array]:
    p, w = np.polynomial.legendre.leggauss(n)
    X, Y = np.meshgrid(p, p, indexing="ij")
    return np.stack([X.ravel(), Y.ravel()], axis=-1), np.outer(w, w).ravel()


def triangle_rule() -> tuple[Array, Array]:
    """Six-point rule, exact for degree 4, on the unit triangle."""
    a, b = 0.445948490915965, 0.091576213509771
    wa, wb = 0.223381589678011 / 2, 0.109951743655322 / 2
    pts = [(a, a), (1 - 2 * a, a), (a, 1 - 2 * a), (b, b), (1 - 2 * b, b), (b, 1 - 2 * b)]
    return np.array(pts), np.array([wa] * 3 + [wb] * 3)


def collapsed_triangle_rule(n: int) -> tuple[Array, Array]:
    """An n x n Gauss rule collapsed onto the unit triangle (Duffy), exact for polynomials
    of degree 2n - 2."""
    p, w = np.polynomial.legendre.leggauss(n)
    u, v = 0.5 * (p + 1.0), 0.5 * (p + 1.0)
    U, V = np.meshgrid(u, v, indexing="ij")
    weights = 0.25 * np.outer(w, w) * (1.0 - U)
    return np.stack([U.ravel(), (V * (1.0 - U)).ravel()], axis=-1), weights.ravel()


_t6_edge, _t6_vertex = 332.0 / 999.0, 1.0 / 999.0

FACE_TYPES: dict[str, FaceType] = {
    ft.name: ft
    for ft in [
        FaceType("L2", 1, np.array([[-1.0], [1.0]]), False, (1, 0), (0.5, 0.5), gauss_line(3)),
        FaceType("L3", 1, np.array([[-1.0], [1.0], [0.0]]), False, (1, 0, 2),
                 (1 / 6, 1 / 6, 2 / 3), gauss_line(4)),
        FaceType("T3", 2, np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), True, (0, 2, 1),
                 (1 / 3,) * 3, triangle_rule()),
        FaceType("T6", 2,
                 np.array([[0, 0], [1, 0], [0, 1], [0.5, 0.5], [0, 0.5], [0.5, 0]], dtype=float),
                 True, (0, 2, 1, 3, 5, 4), (_t6_vertex,) * 3 + (_t6_edge,) * 3, triangle_rule()),
        FaceType("Q4", 2, np.array([[-1.0, -1.0], [1.0, -1.0], [-1.0, 1.0], [1.0, 1.0]]), False,
                 (0, 2, 1, 3), (0.25,) * 4, _gauss_quad(3)),
        FaceType("Q9", 2,
                 np.array([[-1, -1], [1, -1], [-1, 1], [1, 1], [0, -1], [-1, 0], [1, 0], [0, 1],
                           [0, 0]], dtype=float),
                 False, (0, 2, 1, 3, 5, 4, 7, 6, 8),
                 (1 / 36,) * 4 + (1 / 9,) * 4 + (4 / 9,), _gauss_quad(4)),
    ]
}


def surface_vector(tangents: Array) -> Array:
    """Surface Jacobian vector ``m`` from covariant tangents (n, fdim, gdim).

    3D: ``q_,xi x q_,eta``; 2D: ``R q_,xi = (q_,xi_y, -q_,xi_x)``.
    """
    if tangents.shape[1] == 2:
        return np.cross(tangents[:, 0], tangents[:, 1])
    t = tangents[:, 0]
    return np.stack([t[:, 1], -t[:, 0]], axis=-1)


def face_areas(face: FaceType, coords: Array) -> Array:
    """Areas (lengths in 2D) of faces with node coordinates ``coords`` (n_faces, nn, gdim)."""
    pts, wts = face.quadrature
    _, dphi, _ = face.evaluate(pts)
    tangents = np.einsum("qka,fkd->fqad", dphi, coords)
    n_f, n_q = tangents.shape[:2]
    gdim = coords.shape[-1]
    m = surface_vector(tangents.reshape(n_f * n_q, face.fdim, gdim)).reshape(n_f, n_q, gdim)
    return np.linalg.norm(m, axis=-1) @ wts


def revolved_area_shares(face: FaceType, coords: Array) -> Array:
    """Each node's share ``int N_k 2 pi r ds`` (n_faces, nn) [length^2] of the surfaces of
    revolution swept by 2D segments with node coordinates ``coords`` (n_faces, nn, 2) about
    the axis ``r = x[..., 0] = 0``: a node on the axis gets its (small) share too."""
    pts, wts = face.quadrature
    phi, dphi, _ = face.evaluate(pts)
    tangents = np.einsum("qka,fkd->fqad", dphi, coords)
    lengths = np.linalg.norm(tangents[:, :, 0, :], axis=-1)  # (n_faces, n_q)
    r = np.einsum("qk,fk->fq", phi, coords[..., 0])
    return 2.0 * np.pi * np.einsum("fq,q,qk->fk", r * lengths, wts, phi)


def unit_vector(v) -> Array:
    """``v / |v|``, scaled first so that tiny components (1e-200) still give a direction."""
    v = np.asarray(v, dtype=float)
    v = v / np.abs(v).max()
    return v / np.linalg.norm(v)
