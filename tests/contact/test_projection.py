"""Closest-point projection (projection.py; docs/theory.md §3.2, §10.4, §11 #1)."""
import numpy as np
import pytest

from dolfinx_friction.contact.projection import closest_point, project
from dolfinx_friction.contact.shapes import FACE_TYPES

from .helpers import (
    FACES,
    flat_faces,
    random_faces,
    random_interior_xi,
    record,
    rng_for,
    surface_point,
)


def _placed(name, n, seed, gaps, warp=0.15, jitter=0.06, offset=0.5):
    """Faces and slave points at clearances ``gaps`` above known interior points."""
    face = FACE_TYPES[name]
    rng = rng_for("proj", name, seed)
    x = random_faces(face, n, rng, warp=warp, jitter=jitter, offset=offset)
    xi = random_interior_xi(face, n, rng)
    q, nrm, _ = surface_point(face, x, xi)
    g = np.resize(np.asarray(gaps, float), n)
    return face, x, xi, q + g[:, None] * nrm


@pytest.mark.parametrize("name", FACES)
def test_orthogonality_at_interior_projection(name):
    """§11 #1: r . q_,a <~ 1e-13 |r| |q_,a| (warped Q4, curved L3/T6/Q9)."""
    gaps = np.concatenate([np.linspace(-0.1, -0.01, 10), np.linspace(0.01, 0.1, 10)])
    face, x, xi_exact, p = _placed(name, 200, 0, gaps, warp=0.3)
    pr = project(face, p, x)
    assert pr.converged.all() and pr.interior.all()
    q, _, qa = surface_point(face, x, pr.xi)
    r = p - q
    ortho = np.abs(np.einsum("nd,nad->na", r, qa)) / (
        np.linalg.norm(r, axis=1)[:, None] * np.linalg.norm(qa, axis=2))
    worst = record(f"projection orthogonality |r.q_a|/(|r||q_a|) [{name}]", ortho.max())
    # measured <= 2.2e-14 (coordinates O(1), |r| >= 0.01)
    assert worst < 1e-13, worst
    np.testing.assert_allclose(pr.xi, xi_exact, rtol=0, atol=1e-13)


@pytest.mark.parametrize("name", ["Q4", "Q9", "T6", "L3"])
def test_converges_on_warped_and_curved_faces(name):
    """Strongly warped Q4 / curved Q9, T6, L3, both sides of the face, from the centroid."""
    gaps = np.linspace(-0.2, 0.2, 9)
    face, x, xi_exact, p = _placed(name, 300, 1, gaps, warp=0.35, jitter=0.08)
    pr = project(face, p, x)
    assert pr.converged.all() and pr.interior.all()
    err = np.abs(pr.xi - xi_exact).max()
    record(f"projection xi error, warped/curved [{name}]", err)
    assert err < 1e-13
    # a warm start converges to the same point
    pr2 = project(face, p, x, xi0=xi_exact + 0.05)
    np.testing.assert_allclose(pr2.xi, pr.xi, rtol=0, atol=1e-13)


@pytest.mark.parametrize("name", FACES)
def test_small_and_zero_clearance_is_interior(name):
    """Regression: with ``g_N`` tiny or 0 (slave on the face: the usual contact state), the
    distance comparison is pure round-off.  Before the fix in project(), 5-20 % of such
    exact interior projections never converged and were reported off the face."""
    gaps = [0.0, 1e-12, 1e-10, 1e-8, -1e-8, 1e-6, -1e-6, 1e-5, 1e-4, -1e-4]
    for offset in (0.5, 10.0):
        face, x, xi_exact, p = _placed(name, 300, 2, gaps, offset=offset)
        pr = project(face, p, x)
        assert pr.converged.all(), np.flatnonzero(~pr.converged)
        assert pr.interior.all()
        np.testing.assert_allclose(pr.xi, xi_exact, rtol=0, atol=1e-13 * (1 + offset))


@pytest.mark.parametrize("name", FACES)
def test_flat_face_projection_is_analytic(name):
    """Straight-sided flat faces are affine: xi = xi_c + J^+ (p - q(xi_c)), g_N = (p - q) . n."""
    face = FACE_TYPES[name]
    rng = rng_for("flat-proj", name)
    x = flat_faces(face, 100, rng, affine=True)
    d = x.shape[2]
    xc = np.tile(face.centroid, (100, 1))
    qc, nrm, J = surface_point(face, x, xc)  # J = q_,a (n, fdim, d), constant on the face
    # random points anywhere above/below the face (some beyond its edges)
    p = qc + rng.uniform(-1, 1, (100, d))
    xi_ref = xc + np.linalg.solve(np.einsum("nad,nbd->nab", J, J),
                                  np.einsum("nad,nd->na", J, p - qc)[..., None])[..., 0]
    pr = project(face, p, x)
    assert pr.converged.all()
    np.testing.assert_allclose(pr.xi, xi_ref, rtol=0, atol=1e-13)
    inside = face.distance_outside(xi_ref) <= 1e-9
    np.testing.assert_array_equal(pr.interior, inside)
    q, n2, _ = surface_point(face, x, pr.xi)
    g = np.einsum("nd,nd->n", p - q, n2)
    np.testing.assert_allclose(g, np.einsum("nd,nd->n", p - qc, nrm), rtol=0, atol=1e-14)
    np.testing.assert_allclose(np.abs(g), np.linalg.norm(p - q, axis=1), rtol=1e-12)


def _grid(face, m):
    g = np.linspace(0, 1, m) if face.simplex else np.linspace(-1, 1, m)
    if face.fdim == 1:
        return g[:, None]
    X, Y = np.meshgrid(g, g, indexing="ij")
    P = np.stack([X.ravel(), Y.ravel()], axis=-1)
    return P[P.sum(axis=1) <= 1 + 1e-15] if face.simplex else P


def _brute_force(face, p, x, m):
    """Closest sampled point (distance, xi) on a uniform grid of the closed domain."""
    G = _grid(face, m)
    phi, _, _ = face.evaluate(G)
    dist = np.linalg.norm(np.einsum("gk,nkd->ngd", phi, x) - p[:, None], axis=2)
    j = dist.argmin(axis=1)
    return dist[np.arange(len(p)), j], G[j], G


@pytest.mark.parametrize("name", FACES)
def test_points_beyond_the_edge(name):
    """Off-face points: flagged non-interior; closest_point is the closest point of the
    closed face, compared with brute-force sampling (coarse grid, then a fine local one)."""
    face = FACE_TYPES[name]
    rng = rng_for("off", name)
    n = 60
    x = random_faces(face, n, rng)
    # the slave sits above an extrapolated point of the face, beyond an edge or corner
    xi = (rng.uniform(-0.6, 1.4, (4 * n, 2)) if face.simplex
          else rng.uniform(-1.7, 1.7, (4 * n, face.fdim)))
    xi = xi[face.distance_outside(xi) > 0.05][:n]
    assert len(xi) == n
    q, nrm, _ = surface_point(face, x, xi)
    p = q + rng.uniform(-0.2, 0.2, n)[:, None] * nrm
    pr = project(face, p, x)
    assert not pr.interior.any()
    # project() returns the unconstrained stationary point, off the face (here it always
    # converges: measured orthogonality <= 9.4e-14 at the extrapolated surface)
    assert pr.converged.all()
    assert np.all(face.distance_outside(pr.xi) > 1e-9)
    q_s, _, qa_s = surface_point(face, x, pr.xi)
    r_s = p - q_s
    ortho = (np.abs(np.einsum("nd,nad->na", r_s, qa_s))
             / (np.linalg.norm(r_s, axis=1)[:, None] * np.linalg.norm(qa_s, axis=2))).max()
    record(f"off-face stationary point orthogonality [{name}]", ortho)
    assert ortho < 1e-12
    cp = closest_point(face, p, x)
    assert np.all(face.distance_outside(cp) == 0.0)
    q_cp, _, _ = surface_point(face, x, cp)
    d_cp = np.linalg.norm(p - q_cp, axis=1)
    # coarse brute force, then a fine grid around the coarse winner
    m = 2001 if face.fdim == 1 else 201
    d_b, xi_b, G = _brute_force(face, p, x, m)
    spacing = (1.0 if face.simplex else 2.0) / (m - 1)
    fine = np.empty_like(xi_b)
    d_f = np.empty(n)
    for k in range(n):
        local = face.clamp(xi_b[k] + np.linspace(-2, 2, 401 if face.fdim == 1 else 81)[:, None]
                           * spacing if face.fdim == 1 else
                           xi_b[k] + np.stack(np.meshgrid(*[np.linspace(-2, 2, 81) * spacing] * 2,
                                                          indexing="ij"), -1).reshape(-1, 2))
        phi, _, _ = face.evaluate(local)
        dist = np.linalg.norm(phi @ x[k] - p[k], axis=1)
        j = dist.argmin()
        fine[k], d_f[k] = local[j], dist[j]
    # never worse than sampling, and within the sampling resolution of it
    excess = (d_cp - d_f).max()
    record(f"closest_point distance - fine brute force [{name}]", max(excess, 0.0))
    assert excess <= 1e-14
    assert (d_f - d_cp).max() < 1e-6
    dxi = np.abs(cp - fine).max()
    record(f"closest_point |xi - fine brute force xi| [{name}]", dxi)
    assert dxi < 3 * 4 * spacing / 80 + 1e-12  # within a few fine-grid spacings
    # first-order optimality on the closed face: the projected gradient vanishes.
    # closest_point is a projected-gradient method (linear convergence, 60 iterations):
    # measured residual <= 1.2e-8 (T6) for slaves up to ~1 L beyond an edge
    _, _, qa = surface_point(face, x, cp)
    g = np.einsum("nd,nad->na", p - q_cp, qa)  # -grad of |p - q|^2 / 2
    t = 1e-6
    kkt = (np.abs(face.clamp(cp + t * g) - cp).max(axis=1) / t).max()
    record(f"closest_point projected-gradient residual [{name}]", kkt)
    assert kkt < 1e-7
