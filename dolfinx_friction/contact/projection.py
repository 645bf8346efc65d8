"""Closest-point projection of slave points onto master faces (docs/theory.md §3.2).

Newton's method on the orthogonality conditions ``c_a = r . q_,a = 0`` is run
*unconstrained* to machine precision.  The stationary point is an interior
projection when it lies in the face's parametric domain (to ``edge_tol``);
otherwise the point projects off the face (``interior`` is False) and the
element's derivatives, which assume orthogonality, would not hold on the
clamped point: a clamped projection is never passed off as an interior one.
:func:`closest_point` gives the closest point of the closed face for such
points.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dolfinx_friction.contact import backend
from dolfinx_friction.contact.shapes import Array, FaceType, surface_vector

EDGE_TOL = 1e-9  # parametric tolerance for "on the face"


@dataclass
class Projection:
    xi: Array  # (n, fdim) stationary point of the distance (may lie off the face)
    interior: np.ndarray  # (n,) bool: converged, and inside the face
    converged: np.ndarray  # (n,) bool: Newton reached machine precision


def _geometry(face: FaceType, coords: Array, xi: Array):
    phi, dphi, d2phi = face.evaluate(xi)
    q = np.einsum("nk,nkd->nd", phi, coords)
    qa = np.einsum("nka,nkd->nad", dphi, coords)
    qab = np.einsum("nkab,nkd->nabd", d2phi, coords)
    return q, qa, qab


def _newton_step(face: FaceType, x: Array, coords: Array, xi: Array):
    """Newton increment for ``c(xi) = 0``; gradient direction where H is not positive definite."""
    q, qa, qab = _geometry(face, coords, xi)
    r = x - q
    c = np.einsum("nd,nad->na", r, qa)
    H = np.einsum("nad,nbd->nab", qa, qa) - np.einsum("nd,nabd->nab", r, qab)
    eig_min = np.linalg.eigvalsh(H)[:, 0]
    scale = np.einsum("naa->n", np.einsum("nad,nbd->nab", qa, qa))
    good = eig_min > 1e-12 * scale
    step = np.empty_like(xi)
    step[good] = np.linalg.solve(H[good], c[good][..., None])[..., 0]
    step[~good] = c[~good] / scale[~good, None]
    return step, 0.5 * np.einsum("nd,nd->n", r, r)


def project(face: FaceType, x: Array, coords: Array, xi0: Array | None = None,
            max_iter: int = 30, edge_tol: float = EDGE_TOL) -> Projection:
    """Project points ``x`` (n, gdim) onto faces with node coordinates ``coords`` (n, nn, gdim).

    Runs the compiled kernel or :func:`project_numpy`, as :mod:`backend` selects.
    """
    kernels = backend.compiled()
    impl = project_numpy if kernels is None else kernels.project
    return impl(face, x, coords, xi0, max_iter, edge_tol)


def project_numpy(face: FaceType, x: Array, coords: Array, xi0: Array | None = None,
                  max_iter: int = 30, edge_tol: float = EDGE_TOL) -> Projection:
    """:func:`project` in numpy, batched over points (the reference)."""
    n = len(x)
    xi = np.tile(face.centroid, (n, 1)) if xi0 is None else np.array(xi0, dtype=float)
    converged = np.zeros(n, dtype=bool)
    active = np.arange(n)
    for _ in range(max_iter):
        if active.size == 0:
            break
        step, f0 = _newton_step(face, x[active], coords[active], xi[active])
        # damp steps that leave a generous neighbourhood of the face or raise the distance
        length = np.max(np.abs(step), axis=1)
        t = np.minimum(1.0, 1.0 / np.maximum(length, 1e-300))
        trial = xi[active] + t[:, None] * step
        q, _, _ = _geometry(face, coords[active], trial)
        f1 = 0.5 * np.sum((x[active] - q) ** 2, axis=1)
        # below the convergence threshold f1 vs f0 compares round-off only (small g_N):
        # take the full Newton step there, else a sub-ulp half step stalls forever
        worse = (f1 > f0 * (1 + 1e-12) + 1e-300) & (length >= 1e-10)
        trial[worse] = xi[active][worse] + 0.5 * t[worse, None] * step[worse]
        xi[active] = trial
        # a full Newton step this small leaves an error of its square: round-off
        done = (length < 1e-10) & ~worse
        converged[active[done]] = True
        active = active[~done]
    interior = converged & (face.distance_outside(xi) <= edge_tol)
    return Projection(xi, interior, converged)


def clearances(face: FaceType, x: Array, coords: Array, slave: np.ndarray, faces: np.ndarray,
               xi0: Array) -> tuple[Array, Array, Array]:
    """Project points ``x[slave]`` (``x`` (n_s, gdim), ``slave`` (n,)) onto the faces
    ``coords[faces]`` (``coords`` (n_f, nn, gdim)) from ``xi0`` (n, fdim).

    Returns the stationary points ``xi`` (n, fdim), how far (parametric) they lie
    outside their faces (inf where Newton did not converge) and the clearances
    ``g_N = r . m / |m|`` (n,).  Runs the compiled kernel or :func:`clearances_numpy`,
    as :mod:`backend` selects.
    """
    kernels = backend.compiled()
    impl = clearances_numpy if kernels is None else kernels.clearances
    return impl(face, x, coords, slave, faces, xi0)


def clearances_numpy(face: FaceType, x: Array, coords: Array, slave: np.ndarray,
                     faces: np.ndarray, xi0: Array) -> tuple[Array, Array, Array]:
    """:func:`clearances` in numpy (the reference)."""
    x_s, x_f = x[slave], coords[faces]
    proj = project_numpy(face, x_s, x_f, xi0)
    phi, dphi, _ = face.evaluate(proj.xi)
    r = x_s - np.einsum("nk,nkd->nd", phi, x_f)
    m = surface_vector(np.einsum("nka,nkd->nad", dphi, x_f))
    g_N = np.einsum("nd,nd->n", r, m) / np.linalg.norm(m, axis=1)
    outside = np.where(proj.converged, face.distance_outside(proj.xi), np.inf)
    return proj.xi, outside, g_N


def closest_point(face: FaceType, x: Array, coords: Array, xi0: Array | None = None,
                  max_iter: int = 60) -> Array:
    """Closest point of the closed face, by projected gradient iterations with backtracking."""
    xi = face.clamp(np.tile(face.centroid, (len(x), 1)) if xi0 is None else xi0)
    for _ in range(max_iter):
        q, qa, _ = _geometry(face, coords, xi)
        r = x - q
        f0 = 0.5 * np.sum(r * r, axis=1)
        g = np.einsum("nd,nad->na", r, qa)  # = -grad f
        scale = np.einsum("nad,nad->n", qa, qa)
        t = 1.0 / np.maximum(scale, 1e-300)
        for _ in range(30):
            trial = face.clamp(xi + t[:, None] * g)
            qt, _, _ = _geometry(face, coords, trial)
            ok = 0.5 * np.sum((x - qt) ** 2, axis=1) <= f0
            if ok.all():
                break
            t = np.where(ok, t, 0.5 * t)
        moved = np.max(np.abs(trial - xi), axis=1)
        xi = trial
        if np.all(moved < 1e-14):
            break
    return xi
