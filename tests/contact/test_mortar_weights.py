"""The mortar integrals of contact/mortar_weights.py against closed forms (numpy only)."""
from __future__ import annotations

import numpy as np
import pytest

from dolfinx_friction.contact.mortar_weights import mortar_integrals
from dolfinx_friction.contact.shapes import FACE_TYPES, collapsed_triangle_rule, face_areas

L2, L3, T3, Q4, T6, Q9 = (FACE_TYPES[k] for k in ("L2", "L3", "T3", "Q4", "T6", "Q9"))


def test_segments_against_the_closed_form():
    """Slave [0, 1] (N_0 = 1 - x, N_1 = x) against a master segment over [-0.3, 0.4]
    (reversed, lifted by 0.01): int_0^0.4 N_a N_b dx in closed form."""
    xs = np.array([[[0.0, 0.0], [1.0, 0.0]]])
    xm = np.array([[[0.4, 0.01], [-0.3, 0.01]]])
    integrals = mortar_integrals(L2, xs, L2, xm)[0]
    x = np.polynomial.legendre.leggauss(8)
    t, w = 0.2 * (x[0] + 1.0), 0.2 * x[1]
    N_s = np.stack([1 - t, t])
    N_m = np.stack([(t + 0.3) / 0.7, (0.4 - t) / 0.7])
    np.testing.assert_allclose(integrals, np.einsum("aq,bq,q->ab", N_s, N_m, w), rtol=1e-13)


def test_quadratic_master_segment():
    """A slave sub-segment [0, 0.5] against an L3 master over [0, 1]: the integrals of the
    linear times quadratic shape functions (some negative), exactly."""
    xs = np.array([[[0.0, 0.0], [0.5, 0.0]]])
    xm = np.array([[[1.0, 0.0], [0.0, 0.0], [0.5, 0.0]]])
    integrals = mortar_integrals(L2, xs, L3, xm)[0]
    p, w = np.polynomial.legendre.leggauss(6)
    x, w = 0.25 * (p + 1.0), 0.25 * w
    eta = 1.0 - 2.0 * x  # the master's coordinate: node 0 at x = 1
    N_m = np.stack([eta * (eta - 1) / 2, eta * (eta + 1) / 2, 1 - eta ** 2])
    L = np.stack([1 - 2 * x, 2 * x])
    np.testing.assert_allclose(integrals, np.einsum("aq,bq,q->ab", L, N_m, w), rtol=1e-12)
    assert integrals[0, 0] < 0.0


@pytest.mark.parametrize("slave, master", [(Q4, T3), (T3, Q4), (Q4, Q4), (T3, T3), (Q4, Q9),
                                           (T3, T6)])
def test_partition_of_unity_over_a_covering_master(slave, master):
    """A slave face covered by master faces (two triangles or one quadrilateral, larger
    than it, lifted): the integrals summed over the master nodes are the slave shares
    int N_a dA, and over everything the slave face's area (exact on a parallelogram; on a
    general quadrilateral N_a is not polynomial in the plane: 1e-7 here)."""
    corners = {"T3": [[0.1, 0.0], [0.9, 0.2], [0.3, 0.8]],
               "Q4": [[0.0, 0.0], [1.0, 0.1], [0.1, 0.9], [1.1, 1.0]]}[slave.name]
    xs = np.c_[np.array(corners), np.zeros(slave.n_nodes)][None]
    big = np.array([[-1.0, -1.0], [3.0, -1.0], [-1.0, 3.0], [3.0, 3.0]])
    if master.simplex:
        halves = [big[[0, 1, 2]], big[[3, 2, 1]]]
    else:
        halves = [big]
    faces = []
    for h in halves:
        ref = master.nodes  # the face's nodes mapped affinely (straight edges)
        if master.simplex:
            pts = h[0] + ref[:, :1] * (h[1] - h[0]) + ref[:, 1:] * (h[2] - h[0])
        else:
            pts = np.einsum("kc,cd->kd", _bilinear(ref), h)
        faces.append(np.c_[pts, np.full(len(pts), 0.02)])
    xm = np.array([f[list(master.flip)] for f in faces])  # facing the slave
    integrals = mortar_integrals(slave, np.repeat(xs, len(xm), axis=0), master, xm)
    area = face_areas(slave, xs)[0]
    np.testing.assert_allclose(integrals.sum(axis=(0, 2)).sum(), area, rtol=1e-12)
    shares = _shares(slave, xs[0])
    np.testing.assert_allclose(integrals.sum(axis=(0, 2)), shares, rtol=1e-12)


def _bilinear(ref: np.ndarray) -> np.ndarray:
    """Bilinear weights (n, 4) of the corners (-1,-1), (1,-1), (-1,1), (1,1) at ``ref``."""
    a, b = 0.5 * (1 + ref[:, 0]), 0.5 * (1 + ref[:, 1])
    return np.stack([(1 - a) * (1 - b), a * (1 - b), (1 - a) * b, a * b], axis=1)


def _shares(face, x: np.ndarray) -> np.ndarray:
    """int N_a dA over one flat face (a fine Gauss rule)."""
    if face.simplex:
        pts, wts = collapsed_triangle_rule(6)
    else:
        p, w = np.polynomial.legendre.leggauss(6)
        pts = np.stack(np.meshgrid(p, p, indexing="ij"), -1).reshape(-1, 2)
        wts = np.outer(w, w).ravel()
    phi, dphi, _ = face.evaluate(pts)
    t = np.einsum("qka,kd->qad", dphi, x)
    J = np.linalg.norm(np.cross(t[:, 0], t[:, 1]), axis=1)
    return np.einsum("q,qa->a", J * wts, phi)


def test_no_overlap_gives_zero():
    xs = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
    xm = np.array([[[5.0, 5.0, 0.0], [5.0, 6.0, 0.0], [6.0, 5.0, 0.0]]])
    assert not mortar_integrals(T3, xs, T3, xm).any()


def test_quadratic_slave_faces_are_refused():
    with pytest.raises(ValueError, match="linear slave faces, not T6"):
        mortar_integrals(T6, np.zeros((1, 6, 3)), T3, np.zeros((1, 3, 3)))


def test_collapsed_rule_degree():
    """Exact for x^a y^b, a + b <= 2n - 2, on the unit triangle: a! b! / (a + b + 2)!."""
    from math import factorial
    pts, wts = collapsed_triangle_rule(4)
    for a in range(7):
        for b in range(7 - a):
            exact = factorial(a) * factorial(b) / factorial(a + b + 2)
            assert wts @ (pts[:, 0] ** a * pts[:, 1] ** b) == pytest.approx(exact, rel=1e-13)
