"""Master-face shape functions, area weights, face areas and orientation (shapes.py)."""
import numpy as np
import pytest

from dolfinx_friction.contact.shapes import (FACE_TYPES, face_areas, revolved_area_shares,
                                            surface_vector)

from .helpers import FACES, GDIM, flat_faces, random_faces, record, rng_for, surface_point


def random_points(face, n, rng):
    """Random parametric points in the (closed) domain."""
    if face.simplex:
        return rng.dirichlet(np.ones(3), n)[:, 1:]
    return rng.uniform(-1, 1, (n, face.fdim))


@pytest.mark.parametrize("name", FACES)
def test_partition_of_unity_and_zero_sum_derivatives(name):
    face = FACE_TYPES[name]
    xi = random_points(face, 50, rng_for("pou", name))
    phi, dphi, d2phi = face.evaluate(xi)
    assert phi.shape == (50, face.n_nodes)
    assert dphi.shape == (50, face.n_nodes, face.fdim)
    assert d2phi.shape == (50, face.n_nodes, face.fdim, face.fdim)
    np.testing.assert_allclose(phi.sum(axis=1), 1.0, rtol=0, atol=1e-14)
    np.testing.assert_allclose(dphi.sum(axis=1), 0.0, rtol=0, atol=1e-13)
    np.testing.assert_allclose(d2phi.sum(axis=1), 0.0, rtol=0, atol=1e-13)
    # second derivatives are symmetric
    np.testing.assert_array_equal(d2phi, np.swapaxes(d2phi, -1, -2))


@pytest.mark.parametrize("name", FACES)
def test_kronecker_property(name):
    face = FACE_TYPES[name]
    phi, _, _ = face.evaluate(face.nodes)
    np.testing.assert_allclose(phi, np.eye(face.n_nodes), rtol=0, atol=1e-15)
    # the reference nodes lie in the closed domain and the centroid inside it
    assert np.all(face.distance_outside(face.nodes) == 0)
    assert face.distance_outside(face.centroid[None])[0] == 0


@pytest.mark.parametrize("name", FACES)
def test_derivatives_against_finite_differences(name):
    face = FACE_TYPES[name]
    xi = random_points(face, 30, rng_for("dphi", name))
    _, dphi, d2phi = face.evaluate(xi)
    h = 1e-6
    worst1 = worst2 = 0.0
    for a in range(face.fdim):
        e = np.zeros(face.fdim)
        e[a] = h
        pp, dp, _ = face.evaluate(xi + e)
        pm, dm, _ = face.evaluate(xi - e)
        worst1 = max(worst1, np.abs((pp - pm) / (2 * h) - dphi[..., a]).max())
        worst2 = max(worst2, np.abs((dp - dm) / (2 * h) - d2phi[..., a]).max())
    record(f"shape dphi vs FD abs error [{name}]", worst1)
    record(f"shape d2phi vs FD abs error [{name}]", worst2)
    # the bases are at most quadratic per direction: the central difference has no
    # truncation error for phi, so only round-off (~eps/h ~ 1e-10) remains (measured <= 3e-10)
    assert worst1 < 2e-9
    assert worst2 < 2e-9


_WEIGHTS = {  # docs/theory.md §2.1 (T6: CalculiX's code values) and §9/§10.11
    "L2": [0.5, 0.5], "L3": [1 / 6, 1 / 6, 2 / 3], "T3": [1 / 3] * 3,
    "T6": [1 / 999] * 3 + [332 / 999] * 3, "Q4": [0.25] * 4,
    "Q9": [1 / 36] * 4 + [1 / 9] * 4 + [4 / 9],
}


@pytest.mark.parametrize("name", FACES)
def test_area_weights(name):
    face = FACE_TYPES[name]
    w = np.array(face.area_weights)
    assert len(w) == face.n_nodes
    assert np.all(w > 0)
    assert abs(w.sum() - 1.0) < 1e-15
    np.testing.assert_allclose(w, _WEIGHTS[name], rtol=1e-15)
    # quadrature weights integrate 1 over the reference domain
    pts, wts = face.quadrature
    assert abs(wts.sum() - (0.5 if face.simplex else 2.0 ** face.fdim)) < 1e-14
    assert np.all(face.distance_outside(pts) == 0)


def _analytic_flat_area(name, x):
    """Area (length) of straight-sided flat faces from their corners."""
    if name in ("L2", "L3"):
        return np.linalg.norm(x[:, 1] - x[:, 0], axis=1)
    if name in ("T3", "T6"):
        return 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)
    # planar quadrilateral (basix order 0, 1, 3, 2 around the boundary): half the
    # norm of the cross product of the diagonals
    return 0.5 * np.linalg.norm(np.cross(x[:, 3] - x[:, 0], x[:, 2] - x[:, 1]), axis=1)


@pytest.mark.parametrize("name", FACES)
@pytest.mark.parametrize("affine", [True, False], ids=["affine", "general"])
def test_face_areas_exact_for_flat_faces(name, affine):
    face = FACE_TYPES[name]
    x = flat_faces(face, 20, rng_for("flat", name, affine), affine=affine)
    A = face_areas(face, x)
    ref = _analytic_flat_area(name, x)
    err = np.abs(A - ref).max() / ref.max()
    record(f"face_areas flat rel error [{name}]", err)
    assert err < 1e-14


def _fine_area(face, x, n_gauss=48):
    """Reference area by a high-order tensor Gauss rule (Duffy-collapsed on triangles)."""
    g, w = np.polynomial.legendre.leggauss(n_gauss)
    if face.fdim == 1:
        pts, wts = g[:, None], w
    else:
        U, V = np.meshgrid(g, g, indexing="ij")
        W = np.outer(w, w)
        if face.simplex:
            u, v = (U + 1) / 2, (V + 1) / 2
            pts = np.stack([u, v * (1 - u)], axis=-1).reshape(-1, 2)
            wts = (W * (1 - u) / 4).ravel()
        else:
            pts, wts = np.stack([U, V], axis=-1).reshape(-1, 2), W.ravel()
    _, dphi, _ = face.evaluate(pts)
    tang = np.einsum("qka,fkd->fqad", dphi, x)
    nf, nq = tang.shape[:2]
    m = surface_vector(tang.reshape(nf * nq, face.fdim, -1)).reshape(nf, nq, -1)
    return np.linalg.norm(m, axis=-1) @ wts


@pytest.mark.parametrize("name", ["L3", "T6", "Q9"])
def test_face_areas_flat_with_curved_edges(name):
    """Flat faces whose edge/interior nodes are shifted in the plane: ``|m|`` is a
    polynomial that the face's own rule integrates exactly."""
    face = FACE_TYPES[name]
    x = flat_faces(face, 20, rng_for("flat-curved", name), affine=True, in_plane_jitter=0.04)
    A = face_areas(face, x)
    ref = _fine_area(face, x)
    err = np.abs(A - ref).max() / ref.max()
    record(f"face_areas flat curved-edge rel error [{name}]", err)
    assert err < 1e-13


@pytest.mark.parametrize("name", ["L3", "T6", "Q9"])
def test_face_areas_curved_against_fine_reference(name):
    face = FACE_TYPES[name]
    x = random_faces(face, 20, rng_for("curved", name), warp=0.15, jitter=0.05)
    A = face_areas(face, x)
    ref = _fine_area(face, x)
    # the reference is converged (compare two resolutions)
    assert np.abs(_fine_area(face, x, 64) - ref).max() < 1e-14 * ref.max()
    err = np.abs(A - ref).max() / ref.max()
    record(f"face_areas curved rel error vs fine reference [{name}]", err)
    # |m| is not a polynomial on a curved face, so the fixed rule is only accurate
    # to its order: measured 4.2e-6 (L3), 3.1e-5 (T6), 1.9e-6 (Q9) at warp 0.15
    assert err < 3e-4


@pytest.mark.parametrize("name", FACES)
def test_flip_reverses_the_normal(name):
    face = FACE_TYPES[name]
    rng = rng_for("flip", name)
    x = random_faces(face, 10, rng)
    flip = np.array(face.flip)
    assert sorted(flip) == list(range(face.n_nodes))
    xf = x[:, flip]
    xi = random_points(face, 10, rng)
    # the flipped node order re-parametrises the same surface: lines xi -> -xi,
    # faces (xi, eta) -> (eta, xi)
    xi_f = -xi if face.fdim == 1 else xi[:, ::-1]
    q, n, _ = surface_point(face, x, xi)
    qf, nf, _ = surface_point(face, xf, xi_f)
    np.testing.assert_allclose(qf, q, rtol=0, atol=1e-14)
    np.testing.assert_allclose(nf, -n, rtol=0, atol=1e-13)
    np.testing.assert_allclose(face_areas(face, xf), face_areas(face, x), rtol=1e-13)
    # flipping twice restores the order
    np.testing.assert_array_equal(flip[flip], np.arange(face.n_nodes))


@pytest.mark.parametrize("name", ["L2", "T3", "Q4"])
def test_normal_orientation_of_reference_faces(name):
    """The reference face in the plane z = 0 (y = 0 in 2D) has its normal along +z
    (2D: ``R q_,xi`` with ``q_,xi`` along +x gives -y)."""
    face = FACE_TYPES[name]
    x = np.zeros((1, face.n_nodes, GDIM[name]))
    x[0, :, : face.fdim] = face.nodes
    _, n, _ = surface_point(face, x, face.centroid[None])
    expected = np.array([0.0, -1.0]) if face.fdim == 1 else np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(n[0], expected, atol=1e-15)


@pytest.mark.parametrize("name", ["L2", "L3"])
def test_revolved_area_shares(name):
    """``int N_k 2 pi r ds`` of straight segments (one from the axis along r) against a fine
    trapezoid rule, to round-off; their sum is Pappus' area 2 pi r_centroid L of the swept
    surface, and the L2 node on the axis gets 2 pi L^2 / 6.  A curved L3 segment (its midside
    node 0.19 off the chord of length 1): 3.3e-4, the error of the face's 4-point Gauss rule
    (as in ``face_areas``)."""
    face = FACE_TYPES[name]
    coords = [[[0.0, 0.0], [0.3, 0.0]], [[1.0, 0.0], [1.6, 0.8]]]
    if name == "L3":  # the midside node last: on the chord, and off it (curved)
        coords = [[a, b, [(a[0] + b[0]) / 2, (a[1] + b[1]) / 2]] for a, b in coords]
        coords.append([[1.0, 0.0], [1.6, 0.8], [1.5, 0.3]])
    coords = np.array(coords)
    shares = revolved_area_shares(face, coords)
    xi = np.linspace(-1.0, 1.0, 200001)[:, None]
    trapezoid = np.full(len(xi), xi[1, 0] - xi[0, 0])
    trapezoid[[0, -1]] /= 2
    phi, dphi, _ = face.evaluate(xi)
    for i, (c, got) in enumerate(zip(coords, shares)):
        ds = np.linalg.norm(np.einsum("qka,kd->qd", dphi, c), axis=1)
        r = phi @ c[:, 0]
        want = (2 * np.pi * r * ds * trapezoid) @ phi
        np.testing.assert_allclose(got, want, rtol=1e-9 if i < 2 else 4e-4, atol=1e-12)
    straight = coords[:2]
    L = np.linalg.norm(straight[:, 1] - straight[:, 0], axis=1)
    pappus = 2 * np.pi * straight[:, :2, 0].mean(axis=1) * L
    np.testing.assert_allclose(shares[:2].sum(axis=1), pappus, rtol=1e-14)
    if name == "L2":
        assert shares[0, 0] == pytest.approx(2 * np.pi * 0.3 ** 2 / 6, rel=1e-14)
