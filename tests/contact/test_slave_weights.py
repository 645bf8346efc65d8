"""Slave nodal areas and force distribution of quadratic faces (slave_weights.py)."""
import numpy as np
import pytest

from dolfinx_friction.contact.shapes import FACE_TYPES, face_areas
from dolfinx_friction.contact.slave_weights import distribution, is_quadratic, shares

from .helpers import FACES, flat_faces, random_faces, rng_for

QUADRATIC = ("L3", "T6", "Q9")
#: each node's share of a flat face with straight edges: 1/4, 1/2 of a segment; 1/12, 1/4
#: of a T6 face; 1/16, 1/8, 1/4 of a Q9 face (corners, mid-sides, centre)
SHARES = {"L3": (1 / 4, 1 / 4, 1 / 2), "T6": (1 / 12,) * 3 + (1 / 4,) * 3,
          "Q9": (1 / 16,) * 4 + (1 / 8,) * 4 + (1 / 4,)}


def test_only_quadratic_faces_spread_their_forces():
    assert [name for name in FACES if is_quadratic(FACE_TYPES[name])] == list(QUADRATIC)


@pytest.mark.parametrize("name", FACES)
def test_shares_sum_to_the_face_area_and_are_positive(name):
    face = FACE_TYPES[name]
    x = random_faces(face, 20, rng_for("shares", name))
    s = shares(face, x)
    assert s.shape == (20, face.n_nodes)
    assert np.all(s > 0.0)
    # on curved faces the sub-faces' quadrature differs from the face's own only by its
    # (small) integration error of the non-polynomial area density
    np.testing.assert_allclose(s.sum(axis=1), face_areas(face, x), rtol=1e-4)


@pytest.mark.parametrize("name", QUADRATIC)
def test_shares_of_a_flat_face(name):
    face = FACE_TYPES[name]
    x = flat_faces(face, 5, rng_for("flat shares", name))
    area = face_areas(face, x)
    np.testing.assert_allclose(shares(face, x) / area[:, None],
                               np.broadcast_to(SHARES[name], (5, face.n_nodes)), rtol=1e-13)


@pytest.mark.parametrize("name", QUADRATIC)
def test_a_linear_pressure_gives_the_consistent_nodal_forces(name):
    """On a flat face with straight edges, nodal pressures of a linear field p(x) give
    f_i = int N_i p dA, the consistent forces of the quadratic face (uniform p: zero at T6
    corners), computed here with the face's own quadrature."""
    face = FACE_TYPES[name]
    rng = rng_for("linear pressure", name)
    x = flat_faces(face, 6, rng)
    C = distribution(face, x)  # (n, nn_i, nn_k)
    for a, b in ((1.0, 0.0), (0.3, 1.0)):
        grad = b * rng.standard_normal(x.shape[-1])
        p_nodes = a + x @ grad  # (n, nn)
        f = np.einsum("fik,fk->fi", C, p_nodes)
        pts, wts = face.quadrature
        N, _, _ = face.evaluate(pts)
        xq = np.einsum("qk,fkd->fqd", N, x)
        area = face_areas(face, x)
        reference_area = wts.sum()
        exact = np.einsum("fq,qi,q->fi", a + xq @ grad, N, wts) * (area / reference_area)[:, None]
        np.testing.assert_allclose(f, exact, rtol=1e-12, atol=1e-14 * area.max())
    if name == "T6":  # uniform pressure: nothing on the corners
        np.testing.assert_allclose(C.sum(axis=2)[:, :3], 0.0, atol=1e-14)


@pytest.mark.parametrize("name", QUADRATIC)
def test_each_nodes_force_spreads_with_weights_that_sum_to_one(name):
    """T_ik = C_ik / A_k: the columns of C sum to the shares, so a node's force keeps
    its resultant; on curved faces too."""
    face = FACE_TYPES[name]
    x = random_faces(face, 20, rng_for("spread", name))
    C = distribution(face, x)
    s = shares(face, x)
    T = C / s[:, None, :]
    np.testing.assert_allclose(T.sum(axis=1), 1.0, rtol=1e-13)
