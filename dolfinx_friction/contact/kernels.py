"""Compiled per-pair kernels of the contact element (numba), twins of the numpy reference.

The numpy path (:func:`~dolfinx_friction.contact.projection.project_numpy`,
:func:`~dolfinx_friction.contact.element.face_kinematics_numpy`, ...) works on
whole batches with ~60 numpy calls on stacks of tiny matrices; these kernels
run the same mathematics as one loop over pairs: projection (Newton in the face
parameters, same damping and stopping rules), kinematics with all derivatives
(docs/theory.md §3, §5), normal law (§4.1), radial return (§6.3) and the
exact tangent (§7).  Results equal the numpy path's to round-off
(``tests/contact/test_kernels.py``).

The public functions at the end have the numpy path's signatures and return the
same dataclasses; :mod:`dolfinx_friction.contact.backend` chooses between the two.

Conventions of the compiled functions: they take the whole batch arrays (pair
index first, shapes as :class:`~dolfinx_friction.contact.element.Kinematics`)
and the pair ``p``, and small scratch arrays allocated once per batch; the
element dofs of a derivative are flattened, ``j = i d + l`` (node ``i``,
component ``l``), so ``dnormal`` is (n, d, nodes d).  No array views or tuples of
arrays in the per-pair code: numba reference-counts each of them with an atomic
operation, which cost half of the time in a first version.

Importing this module needs numba; each kernel is compiled at its first call
and cached on disk (``cache=True``), or compiled in every process where numba
finds no writable cache directory.
"""
from __future__ import annotations

import math
from typing import Optional

import numba
import numpy as np

from dolfinx_friction.contact.element import ContactParameters, ElementResult, Kinematics
from dolfinx_friction.contact.friction import FrictionState
from dolfinx_friction.contact.laws import _EXP_CAP, Exponential, Law, Linear, Tabular
from dolfinx_friction.contact.projection import EDGE_TOL, Projection
from dolfinx_friction.contact.shapes import Array, FaceType, unit_vector

OPEN, STICK, SLIP = 0, 1, 2  # as in element.py
FACE_CODES = {"L2": 0, "L3": 1, "T3": 2, "T6": 3, "Q4": 4, "Q9": 5}
_LINEAR, _EXPONENTIAL, _TABULAR = 0, 1, 2
MAX_ITER = 30  # projection's Newton iterations, as project_numpy's default


def _jit(func):
    """``numba.njit(cache=True)``; without the on-disk cache where no cache directory is
    writable (numba then refuses ``cache=True`` when decorating).  Division by zero gives
    inf/nan as in numpy (``error_model="numpy"``)."""
    try:
        return numba.njit(cache=True, error_model="numpy")(func)
    except RuntimeError:
        return numba.njit(error_model="numpy")(func)


# ----------------------------------------------------------------------------- shapes
# (i, j) 1D node indices of the tensor-product nodes of Q4 (first 4) and Q9
_TENSOR_ORDER = np.array([[0, 0], [1, 0], [0, 1], [1, 1], [2, 0], [0, 2], [1, 2], [2, 1], [2, 2]])
_T6_HESSIAN = np.array([[[4, 4], [4, 4]], [[4, 0], [0, 0]], [[0, 0], [0, 4]],
                        [[0, 4], [4, 0]], [[0, -4], [-4, -8]], [[-8, -4], [-4, 0]]], dtype=float)


@_jit
def _fdim(code):
    return 1 if code <= 1 else 2


@_jit
def _line(quadratic, j, x):
    """Node ``j`` of the 1D basis (linear: nodes -1, 1; quadratic: -1, 1, 0) at ``x``:
    value, first and second derivative."""
    if not quadratic:
        s = 1.0 if j == 1 else -1.0
        return 0.5 * (1.0 + s * x), 0.5 * s, 0.0
    if j == 2:
        return 1.0 - x * x, -2.0 * x, -2.0
    s = 1.0 if j == 1 else -1.0
    return 0.5 * x * (x + s), x + 0.5 * s, 1.0


@_jit
def _shape(code, x, y, phi, dphi, d2phi):
    """Shape functions of face type ``code`` at ``xi = (x, y)`` (``y`` unused for segments)
    into ``phi`` (nn,), ``dphi`` (nn, 2) and ``d2phi`` (nn, 2, 2); shapes.py's node order."""
    if code <= 1:  # L2, L3
        for k in range(code + 2):
            phi[k], dphi[k, 0], d2phi[k, 0, 0] = _line(code == 1, k, x)
    elif code >= 4:  # Q4, Q9
        quadratic = code == 5
        for k in range(9 if quadratic else 4):
            vx, dx, ddx = _line(quadratic, _TENSOR_ORDER[k, 0], x)
            vy, dy, ddy = _line(quadratic, _TENSOR_ORDER[k, 1], y)
            phi[k] = vx * vy
            dphi[k, 0], dphi[k, 1] = dx * vy, vx * dy
            d2phi[k, 0, 0], d2phi[k, 1, 1] = ddx * vy, vx * ddy
            d2phi[k, 0, 1] = d2phi[k, 1, 0] = dx * dy
    elif code == 2:  # T3
        phi[0], phi[1], phi[2] = 1.0 - x - y, x, y
        dphi[0, 0], dphi[0, 1], dphi[1, 0], dphi[1, 1] = -1.0, -1.0, 1.0, 0.0
        dphi[2, 0], dphi[2, 1] = 0.0, 1.0
        for k in range(3):
            d2phi[k, 0, 0] = d2phi[k, 0, 1] = d2phi[k, 1, 0] = d2phi[k, 1, 1] = 0.0
    else:  # T6: vertices (0,0), (1,0), (0,1); edges (1,2), (0,2), (0,1)
        z = 1.0 - x - y
        phi[0], phi[1], phi[2] = z * (2 * z - 1), x * (2 * x - 1), y * (2 * y - 1)
        phi[3], phi[4], phi[5] = 4 * x * y, 4 * y * z, 4 * x * z
        dphi[0, 0] = dphi[0, 1] = 1.0 - 4.0 * z
        dphi[1, 0], dphi[1, 1] = 4 * x - 1, 0.0
        dphi[2, 0], dphi[2, 1] = 0.0, 4 * y - 1
        dphi[3, 0], dphi[3, 1] = 4 * y, 4 * x
        dphi[4, 0], dphi[4, 1] = -4 * y, 4 * (z - y)
        dphi[5, 0], dphi[5, 1] = 4 * (z - x), -4 * x
        for k in range(6):
            for a in range(2):
                for b in range(2):
                    d2phi[k, a, b] = _T6_HESSIAN[k, a, b]


@_jit
def _distance_outside(code, x, y):
    """How far (parametric) ``xi = (x, y)`` lies outside the face's domain (0 inside)."""
    if code == 2 or code == 3:
        out = max(-x, -y, x + y - 1.0)
    else:
        out = abs(x) - 1.0
        if code >= 4:
            out = max(out, abs(y) - 1.0)
    return max(out, 0.0)


@_jit
def _geometry(code, coords, x, y, phi, dphi, d2phi, q, qa, qab):
    """Point ``q`` (d,), tangents ``qa`` (2, d) and ``qab`` (2, 2, d) (first fdim rows) of the
    face with node coordinates ``coords`` (nn, d) at ``xi = (x, y)``, with the shape functions
    (:func:`_shape`)."""
    _shape(code, x, y, phi, dphi, d2phi)
    nn, d = coords.shape
    surface = _fdim(code) == 2
    for l in range(d):
        s = s0 = s1 = s00 = s01 = s11 = 0.0
        for k in range(nn):
            c = coords[k, l]
            s += phi[k] * c
            s0 += dphi[k, 0] * c
            s00 += d2phi[k, 0, 0] * c
            if surface:
                s1 += dphi[k, 1] * c
                s01 += d2phi[k, 0, 1] * c
                s11 += d2phi[k, 1, 1] * c
        q[l], qa[0, l], qab[0, 0, l] = s, s0, s00
        if surface:
            qa[1, l], qab[0, 1, l], qab[1, 0, l], qab[1, 1, l] = s1, s01, s01, s11


@_jit
def _half_squared_distance(x, q):
    s = 0.0
    for l in range(len(x)):
        s += (x[l] - q[l]) ** 2
    return 0.5 * s


# ----------------------------------------------------------------------------- projection
@_jit
def _newton_step(fdim, x, q, qa, qab):
    """Newton increment (two components, the second 0 for segments) for ``c_a = r . q_,a = 0``;
    the gradient direction ``c / tr(q_,a . q_,b)`` where the Hessian
    ``H_ab = q_,a . q_,b - r . q_,ab`` is not positive definite (as projection.py)."""
    c0 = c1 = H00 = H01 = H11 = scale = 0.0
    for l in range(len(x)):
        r = x[l] - q[l]
        c0 += r * qa[0, l]
        H00 += qa[0, l] * qa[0, l] - r * qab[0, 0, l]
        scale += qa[0, l] * qa[0, l]
        if fdim == 2:
            c1 += r * qa[1, l]
            H01 += qa[0, l] * qa[1, l] - r * qab[0, 1, l]
            H11 += qa[1, l] * qa[1, l] - r * qab[1, 1, l]
            scale += qa[1, l] * qa[1, l]
    if fdim == 1:
        eig_min = H00
    else:
        eig_min = 0.5 * (H00 + H11) - math.sqrt(0.25 * (H00 - H11) ** 2 + H01 * H01)
    if not eig_min > 1e-12 * scale:
        return c0 / scale, c1 / scale
    if fdim == 1:
        return c0 / H00, 0.0
    det = H00 * H11 - H01 * H01
    return (H11 * c0 - H01 * c1) / det, (H00 * c1 - H01 * c0) / det


@_jit
def _project_one(code, x, coords, xi0, xi1, max_iter, phi, dphi, d2phi, q, qa, qab):
    """Project ``x`` (d,) onto the face ``coords`` (nn, d) from ``xi = (xi0, xi1)``.

    projection.py's iteration for one point: damped Newton, converged when a
    full step is below 1e-10.  Returns ``(converged, xi0, xi1)``, and leaves
    the geometry (:func:`_geometry`) evaluated at the returned point.
    """
    fdim = _fdim(code)
    _geometry(code, coords, xi0, xi1, phi, dphi, d2phi, q, qa, qab)
    for _ in range(max_iter):
        f0 = _half_squared_distance(x, q)
        step0, step1 = _newton_step(fdim, x, q, qa, qab)
        length = max(abs(step0), abs(step1))
        t = min(1.0, 1.0 / max(length, 1e-300))
        trial0, trial1 = xi0 + t * step0, xi1 + t * step1
        _geometry(code, coords, trial0, trial1, phi, dphi, d2phi, q, qa, qab)
        # below the convergence threshold f1 vs f0 compares round-off only: full step
        worse = (_half_squared_distance(x, q) > f0 * (1 + 1e-12) + 1e-300
                 and length >= 1e-10)
        if worse:
            trial0, trial1 = xi0 + 0.5 * t * step0, xi1 + 0.5 * t * step1
            _geometry(code, coords, trial0, trial1, phi, dphi, d2phi, q, qa, qab)
        xi0, xi1 = trial0, trial1
        if length < 1e-10 and not worse:
            return True, xi0, xi1
    return False, xi0, xi1


@_jit
def _gather_point(p, X_s, u_s, X_f, u_f, xs, xf):
    """Current slave point ``xs`` (d,) and face nodes ``xf`` (nn, d) of pair ``p``."""
    nn, d = xf.shape
    for l in range(d):
        xs[l] = X_s[p, l] + u_s[p, l]
        for k in range(nn):
            xf[k, l] = X_f[p, k, l] + u_f[p, k, l]


@_jit
def _project_pair(p, code, xs, xf, xi, max_iter, edge_tol, converged, interior,
                  phi, dphi, d2phi, q, qa, qab):
    """Project pair ``p`` (points gathered in ``xs``, ``xf``) from ``xi[p]`` (n, fdim), in place;
    fills ``converged[p]``, ``interior[p]``."""
    two = _fdim(code) == 2
    ok, xi0, xi1 = _project_one(code, xs, xf, xi[p, 0], xi[p, 1] if two else 0.0, max_iter,
                                phi, dphi, d2phi, q, qa, qab)
    xi[p, 0] = xi0
    if two:
        xi[p, 1] = xi1
    converged[p] = ok
    interior[p] = ok and _distance_outside(code, xi0, xi1) <= edge_tol


@_jit
def _project_batch(code, x, coords, xi, max_iter, edge_tol, converged, interior):
    """Project points ``x`` (n, d) onto faces ``coords`` (n, nn, d); ``xi`` (n, fdim) is the
    start and receives the result; fills ``converged``, ``interior`` (n,)."""
    n, nn, d = coords.shape
    phi, dphi, d2phi = np.empty(nn), np.empty((nn, 2)), np.empty((nn, 2, 2))
    q, qa, qab = np.empty(d), np.empty((2, d)), np.empty((2, 2, d))
    xs, xf = np.empty(d), np.empty((nn, d))
    for p in range(n):
        for l in range(d):
            xs[l] = x[p, l]
            for k in range(nn):
                xf[k, l] = coords[p, k, l]
        _project_pair(p, code, xs, xf, xi, max_iter, edge_tol, converged, interior,
                      phi, dphi, d2phi, q, qa, qab)


@_jit
def _clearance_batch(code, x, coords, slave, faces, xi, max_iter, outside, g_N):
    """Project points ``x[slave[p]]`` (``x`` (n_s, d)) onto faces ``coords[faces[p]]``
    (``coords`` (n_f, nn, d)) from ``xi`` (n, fdim), in place; fills ``outside`` (inf where
    Newton did not converge) and the clearances ``g_N`` (n,) (projection.py's clearances)."""
    nn, d = coords.shape[1], coords.shape[2]
    fdim = _fdim(code)
    phi, dphi, d2phi = np.empty(nn), np.empty((nn, 2)), np.empty((nn, 2, 2))
    q, qa, qab = np.empty(d), np.empty((2, d)), np.empty((2, 2, d))
    xs, xf, m = np.empty(d), np.empty((nn, d)), np.empty(d)
    dm_dxi, M = np.empty((2, d)), np.empty((2, d, d))  # _surface_vector's, unused here
    for p in range(len(slave)):
        s, f = slave[p], faces[p]
        for l in range(d):
            xs[l] = x[s, l]
            for k in range(nn):
                xf[k, l] = coords[f, k, l]
        ok, xi0, xi1 = _project_one(code, xs, xf, xi[p, 0], xi[p, 1] if fdim == 2 else 0.0,
                                    max_iter, phi, dphi, d2phi, q, qa, qab)
        xi[p, 0] = xi0
        if fdim == 2:
            xi[p, 1] = xi1
        outside[p] = _distance_outside(code, xi0, xi1) if ok else np.inf
        _surface_vector(fdim, qa, qab, m, dm_dxi, M)
        r_m = m_m = 0.0
        for l in range(d):
            r_m += (xs[l] - q[l]) * m[l]
            m_m += m[l] * m[l]
        g_N[p] = r_m / math.sqrt(m_m)


# ----------------------------------------------------------------------------- kinematics
@_jit
def _surface_vector(fdim, qa, qab, m, dm_dxi, M):
    """Surface vector ``m`` (d,), ``dm/dxi^a`` (2, d) and ``dm/dq_,a`` ``M`` (2, d, d).

    3D: ``m = q_,1 x q_,2``, ``M_1 = -[q_,2]x``, ``M_2 = [q_,1]x``; 2D: ``m = R q_,1``,
    ``M_1 = R`` with ``R = [[0, 1], [-1, 0]]``."""
    if fdim == 1:
        m[0], m[1] = qa[0, 1], -qa[0, 0]
        dm_dxi[0, 0], dm_dxi[0, 1] = qab[0, 0, 1], -qab[0, 0, 0]
        M[0, 0, 0], M[0, 0, 1], M[0, 1, 0], M[0, 1, 1] = 0.0, 1.0, -1.0, 0.0
        return
    for k in range(3):
        k1, k2 = (k + 1) % 3, (k + 2) % 3
        m[k] = qa[0, k1] * qa[1, k2] - qa[0, k2] * qa[1, k1]
        dm_dxi[0, k] = (qab[0, 0, k1] * qa[1, k2] - qab[0, 0, k2] * qa[1, k1]
                        + qa[0, k1] * qab[0, 1, k2] - qa[0, k2] * qab[0, 1, k1])
        dm_dxi[1, k] = (qab[0, 1, k1] * qa[1, k2] - qab[0, 1, k2] * qa[1, k1]
                        + qa[0, k1] * qab[1, 1, k2] - qa[0, k2] * qab[1, 1, k1])
    for a in range(2):  # M_a = sign [v]x with v = q_,(other)
        sign, b = (-1.0, 1) if a == 0 else (1.0, 0)
        v0, v1, v2 = sign * qa[b, 0], sign * qa[b, 1], sign * qa[b, 2]
        M[a, 0, 0], M[a, 0, 1], M[a, 0, 2] = 0.0, -v2, v1
        M[a, 1, 0], M[a, 1, 1], M[a, 1, 2] = v2, 0.0, -v0
        M[a, 2, 0], M[a, 2, 1], M[a, 2, 2] = -v1, v0, 0.0


@_jit
def _sensitivities(p, fdim, r, qa, qab, phi_e, dphi_e, dxi):
    """Projection sensitivities ``dxi[p]`` (fdim, nodes d): ``A dxi/du_i = b_i`` with
    ``A_ab = -q_,a.q_,b + r.q_,ab``, ``b_i = phi_i q_,a - phi_i,a r`` (§3.5)."""
    d = len(r)
    nodes = phi_e.shape[1]
    A00 = A01 = A10 = A11 = 0.0
    for l in range(d):
        A00 += r[l] * qab[0, 0, l] - qa[0, l] * qa[0, l]
        if fdim == 2:
            A01 += r[l] * qab[0, 1, l] - qa[0, l] * qa[1, l]
            A10 += r[l] * qab[1, 0, l] - qa[1, l] * qa[0, l]
            A11 += r[l] * qab[1, 1, l] - qa[1, l] * qa[1, l]
    if fdim == 1:
        i00, i01, i10, i11 = 1.0 / A00, 0.0, 0.0, 0.0
    else:
        det = A00 * A11 - A01 * A10
        i00, i01, i10, i11 = A11 / det, -A01 / det, -A10 / det, A00 / det
    for i in range(nodes):
        for l in range(d):
            b0 = phi_e[p, i] * qa[0, l] - dphi_e[p, i, 0] * r[l]
            if fdim == 1:
                dxi[p, 0, i * d + l] = i00 * b0
            else:
                b1 = phi_e[p, i] * qa[1, l] - dphi_e[p, i, 1] * r[l]
                dxi[p, 0, i * d + l] = i00 * b0 + i01 * b1
                dxi[p, 1, i * d + l] = i10 * b0 + i11 * b1


@_jit
def _normal_derivatives(p, fdim, r, qa, m, dm_dxi, M, dm, normal, dphi_e, dxi, phi_e,
                        dnormal, dg_N):
    """Unit normal ``normal[p]`` (d,), ``dnormal[p] = (I - n n) dm / |m|`` (d, nodes d) and
    ``dg_N[p] = n . dr + r . dn`` (nodes d,) from ``m``, its derivatives (see
    :func:`_surface_vector`) and ``dxi[p]`` (§3.6); ``dm`` (d,) is scratch.  Returns g_N."""
    d = len(r)
    nodes = phi_e.shape[1]
    m_norm = 0.0
    for k in range(d):
        m_norm += m[k] * m[k]
    m_norm = math.sqrt(m_norm)
    g_N = n_qa0 = n_qa1 = 0.0  # n . q_,a: zero up to round-off at an orthogonal projection
    for k in range(d):
        normal[p, k] = m[k] / m_norm
        g_N += r[k] * normal[p, k]
        n_qa0 += normal[p, k] * qa[0, k]
        if fdim == 2:
            n_qa1 += normal[p, k] * qa[1, k]
    for i in range(nodes):
        for l in range(d):
            j = i * d + l
            n_dm = 0.0
            for k in range(d):
                dm[k] = dm_dxi[0, k] * dxi[p, 0, j] + dphi_e[p, i, 0] * M[0, k, l]
                if fdim == 2:
                    dm[k] += dm_dxi[1, k] * dxi[p, 1, j] + dphi_e[p, i, 1] * M[1, k, l]
                n_dm += normal[p, k] * dm[k]
            s = -phi_e[p, i] * normal[p, l] - n_qa0 * dxi[p, 0, j]
            if fdim == 2:
                s -= n_qa1 * dxi[p, 1, j]
            for k in range(d):
                dnormal[p, k, j] = (dm[k] - normal[p, k] * n_dm) / m_norm
                s += r[k] * dnormal[p, k, j]
            dg_N[p, j] = s
    return g_N


@_jit
def _relative_displacement(p, fdim, consistent, u_s, u_f, phi_e, dphi_e, dxi, w, dw):
    """``w[p] = u_p - sum phi_k u_k`` (d,) and ``dw[p]`` (d, nodes d): ``-phi_i I``, minus
    ``(du/dxi^a) (x) dxi^a`` with option (b) ``consistent`` (§5.2, §5.4)."""
    nn, d = u_f.shape[1], u_f.shape[2]
    nodes = nn + 1
    for k in range(d):
        s = u_s[p, k]
        du0 = du1 = 0.0  # du/dxi^a of the master, component k
        for i in range(nn):
            s -= phi_e[p, i] * u_f[p, i, k]
            du0 += dphi_e[p, i, 0] * u_f[p, i, k]
            if fdim == 2:
                du1 += dphi_e[p, i, 1] * u_f[p, i, k]
        w[p, k] = s
        if not consistent:
            du0 = du1 = 0.0
        for i in range(nodes):
            for l in range(d):
                j = i * d + l
                s = -phi_e[p, i] if k == l else 0.0
                s -= du0 * dxi[p, 0, j]
                if fdim == 2:
                    s -= du1 * dxi[p, 1, j]
                dw[p, k, j] = s


@_jit
def _face_batch(code, X_s, u_s, X_f, u_f, xi, consistent, max_iter, edge_tol, converged,
                interior, normal, g_N, dg_N, dnormal, phi_e, dphi_e, dxi, w, dw):
    """Projection and kinematics of ``n`` slave nodes (``X_s, u_s`` (n, d)) on their faces
    (``X_f, u_f`` (n, nn, d)); ``xi`` (n, fdim) is the projection's start and result.
    Outputs as :class:`~dolfinx_friction.contact.element.Kinematics`, with ``dg_N`` (n, nd),
    ``dnormal``, ``dw`` (n, d, nd), ``dxi`` (n, fdim, nd) flattened (``nd = nodes d``)."""
    n, nn, d = X_f.shape
    fdim = _fdim(code)
    phi, dphi, d2phi = np.empty(nn), np.empty((nn, 2)), np.empty((nn, 2, 2))
    q, qa, qab = np.empty(d), np.empty((2, d)), np.empty((2, 2, d))
    xs, xf, r, m, dm = np.empty(d), np.empty((nn, d)), np.empty(d), np.empty(d), np.empty(d)
    dm_dxi, M = np.empty((2, d)), np.empty((2, d, d))
    for p in range(n):
        _gather_point(p, X_s, u_s, X_f, u_f, xs, xf)
        _project_pair(p, code, xs, xf, xi, max_iter, edge_tol, converged, interior,
                      phi, dphi, d2phi, q, qa, qab)
        for k in range(nn):  # the geometry is at the projection
            phi_e[p, k] = phi[k]
            for a in range(fdim):
                dphi_e[p, k, a] = dphi[k, a]
        phi_e[p, nn] = -1.0
        for a in range(fdim):
            dphi_e[p, nn, a] = 0.0
        for l in range(d):
            r[l] = xs[l] - q[l]
        _surface_vector(fdim, qa, qab, m, dm_dxi, M)
        _sensitivities(p, fdim, r, qa, qab, phi_e, dphi_e, dxi)
        g_N[p] = _normal_derivatives(p, fdim, r, qa, m, dm_dxi, M, dm, normal, dphi_e, dxi,
                                     phi_e, dnormal, dg_N)
        _relative_displacement(p, fdim, consistent, u_s, u_f, phi_e, dphi_e, dxi, w, dw)


@_jit
def _rigid_batch(plane, X_s, u_s, U, point, axis_projector, unit, radius,
                 normal, g_N, dg_N, dnormal, phi, w, dw):
    """Kinematics of slave nodes (n, d) against a rigid plane (``point``, unit normal ``unit``)
    or a sphere / cylinder (``point``: center or axis point, ``axis_projector`` (d, d): I or
    I - a a, ``radius``) translated by ``U`` (n, d).  Outputs as rigid_kinematics."""
    n, d = X_s.shape
    v, dn = np.empty(d), np.zeros((d, d))
    for p in range(n):
        for l in range(d):
            v[l] = X_s[p, l] + u_s[p, l] - (point[l] + U[p, l])
        if plane:
            g_N[p] = 0.0
            for k in range(d):
                normal[p, k] = unit[k]
                g_N[p] += v[k] * unit[k]
        else:
            rho = 0.0
            for k in range(d):
                normal[p, k] = 0.0  # v @ axis_projector, normalised below
                for l in range(d):
                    normal[p, k] += v[l] * axis_projector[l, k]
                rho += normal[p, k] * normal[p, k]
            rho = math.sqrt(rho)
            for k in range(d):
                normal[p, k] /= rho
            g_N[p] = rho - radius
            for k in range(d):
                for l in range(d):
                    dn[k, l] = (axis_projector[k, l] - normal[p, k] * normal[p, l]) / rho
        phi[p, 0], phi[p, 1] = 1.0, -1.0
        for k in range(d):
            w[p, k] = u_s[p, k] - U[p, k]
            dg_N[p, 0, k], dg_N[p, 1, k] = -normal[p, k], normal[p, k]
            for l in range(d):
                dnormal[p, k, 0, l], dnormal[p, k, 1, l] = -dn[k, l], dn[k, l]
                dw[p, k, 0, l] = -1.0 if k == l else 0.0
                dw[p, k, 1, l] = 1.0 if k == l else 0.0


# ----------------------------------------------------------------------------- laws
@_jit
def _normal_force_batch(kind, c, table_x, table_p, g, area, F, dF):
    """``F_N`` and ``dF_N/dg_N`` (n,) at clearances ``g`` (laws.py): linear (``c = (K, eps)``),
    exponential (``c = (beta, p0)``, capped at e^23) or tabular (``table_x``, ``table_p``)."""
    for p in range(len(g)):
        d = -g[p]
        if kind == _LINEAR:
            K, eps = c[0], c[1]
            z = d / eps
            h = 0.5 + math.atan(z) / math.pi
            F[p] = area[p] * (K * d * h)
            dF[p] = -area[p] * (K * h + K * z / (math.pi * (1.0 + z * z)))
        elif kind == _EXPONENTIAL:
            beta, p0 = c[0], c[1]
            if p0 < 1e-30:
                F[p], dF[p] = 0.0, 0.0
                continue
            prod = area[p] * p0
            if prod > 0.0 and beta * d > _EXP_CAP - math.log(prod):
                F[p], dF[p] = math.exp(_EXP_CAP), 0.0
            else:
                e = math.exp(min(beta * d, 700.0))
                F[p] = area[p] * (p0 * e)
                dF[p] = -area[p] * (beta * p0 * e)
        else:
            value, slope = _table(table_x, table_p, d)
            F[p] = area[p] * value
            dF[p] = -area[p] * slope


@_jit
def _table(x, y, d):
    """Piecewise linear ``y(d)`` through ``(x, y)``, constant outside; value and slope
    (0 outside ``[x_0, x_last)``)."""
    last = len(x) - 1
    if d < x[0]:
        return y[0], 0.0
    if d >= x[last]:
        return y[last], 0.0
    j = 0
    while x[j + 1] <= d:
        j += 1
    slope = (y[j + 1] - y[j]) / (x[j + 1] - x[j])
    return slope * (d - x[j]) + y[j], slope


# ----------------------------------------------------------------------------- evaluation
@_jit
def _normal_part(p, normal, dg_N, dnormal, F_N, dF_dg, F_p, D, dF_N):
    """Normal force ``F_p = -F_N n`` (d,), ``dF_N`` (nd,) and
    ``D = -n (x) dF_N - F_N dn`` (d, nd) of pair ``p`` (§4.3, §4.4)."""
    d, nd = D.shape
    for j in range(nd):
        dF_N[j] = dF_dg[p] * dg_N[p, j]
    for k in range(d):
        F_p[k] = -F_N[p] * normal[p, k]
        for j in range(nd):
            D[k, j] = -normal[p, k] * dF_N[j] - F_N[p] * dnormal[p, k, j]


@_jit
def _friction(p, normal, dnormal, w, dw, F_N, K_t, mu, h_w, h_gT, h_gp, F_T, g_T, g_p,
              s, F_trial, e, G, n_G, D, dF_N):
    """Radial return (§6.3) of pair ``p`` into ``F_T[p], g_T[p], g_p[p]`` (d,); adds
    ``dF_T/du`` (§7.2) to ``D`` (d, nd).  ``s, F_trial, e`` (d,), ``G`` (d, nd), ``n_G``
    (nd,) are scratch.  Returns whether the pair slips."""
    d, nd = D.shape
    s_N = 0.0
    for k in range(d):
        s[k] = w[p, k] - h_w[p, k]
        s_N += s[k] * normal[p, k]
    norm = 0.0
    for k in range(d):
        g_T[p, k] = h_gT[p, k] + s[k] - s_N * normal[p, k]
        F_trial[k] = K_t * (g_T[p, k] - h_gp[p, k])
        norm += F_trial[k] * F_trial[k]
    norm = math.sqrt(norm)
    limit = mu * abs(F_N)
    slip = norm >= limit and norm > 0.0
    for k in range(d):
        e[k] = F_trial[k] / norm if slip else 0.0
        F_T[p, k] = limit * e[k] if slip else F_trial[k]
        g_p[p, k] = h_gp[p, k] + (norm - limit) / K_t * e[k] if slip else h_gp[p, k]

    # G = dg_T/du (§5.4) = (I - n n) dw - n (x) s.dn - s_N dn
    for j in range(nd):
        n_G[j] = 0.0
        for c in range(d):
            n_G[j] += normal[p, c] * dw[p, c, j] + s[c] * dnormal[p, c, j]
    for k in range(d):
        for j in range(nd):
            G[k, j] = dw[p, k, j] - normal[p, k] * n_G[j] - s_N * dnormal[p, k, j]
    if not slip:
        for k in range(d):
            for j in range(nd):
                D[k, j] += K_t * G[k, j]
        return False
    factor = mu * abs(F_N) * K_t / norm
    sign = 1.0 if F_N > 0.0 else (-1.0 if F_N < 0.0 else 0.0)
    for j in range(nd):  # slip: factor (I - e e) G + mu e (x) sign(F_N) dF_N
        e_G = 0.0
        for c in range(d):
            e_G += e[c] * G[c, j]
        for k in range(d):
            D[k, j] += factor * (G[k, j] - e[k] * e_G) + mu * e[k] * (sign * dF_N[j])
    return True


@_jit
def _element_arrays(p, phi, dphi, dxi, F_p, D, B, f, K):
    """``f[p] = -phi (x) F_p`` (nodes, d) and ``K[p] = -phi (x) D - (dphi . dxi) (x) F_p``
    (nd, nd); ``B`` (nodes, nd) is scratch for ``sum_a phi_k,a dxi^a``."""
    nodes, d = f.shape[1], f.shape[2]
    nd, fdim = nodes * d, dxi.shape[1]  # fdim: 0 (rigid), 1 or 2
    for k in range(nodes):
        for j in range(nd):
            B[k, j] = 0.0 if fdim == 0 else dphi[p, k, 0] * dxi[p, 0, j]
            if fdim == 2:
                B[k, j] += dphi[p, k, 1] * dxi[p, 1, j]
        for c in range(d):
            f[p, k, c] = -phi[p, k] * F_p[c]
            for j in range(nd):
                K[p, k * d + c, j] = -phi[p, k] * D[c, j] - F_p[c] * B[k, j]


@_jit
def _evaluate_batch(normal, g, dg_N, dnormal, phi, dphi, dxi, w, dw, F_N, dF_dg, area, mu,
                    stick_slope, friction, h_w, h_gT, h_gp, f, K, F_T, g_T, g_p, status):
    """Forces ``f`` (n, nodes, d), tangents ``K`` (n, nd, nd) and statuses of ``n`` elements at
    (offset) clearances ``g``; with ``friction``, the radial return from the history
    ``(h_w, h_gT, h_gp)`` into ``F_T, g_T, g_p`` (n, d) (the history and trial arrays are
    unused placeholders without).  Kinematics flattened as :func:`_face_batch`'s."""
    n, d, nd = dnormal.shape
    nodes = nd // d
    F_p, s, F_trial, e = np.empty(d), np.empty(d), np.empty(d), np.empty(d)
    D, G, dF_N, n_G, B = (np.empty((d, nd)), np.empty((d, nd)), np.empty(nd), np.empty(nd),
                          np.empty((nodes, nd)))
    for p in range(n):
        _normal_part(p, normal, dg_N, dnormal, F_N, dF_dg, F_p, D, dF_N)
        status[p] = OPEN if g[p] > 0.0 else SLIP
        if friction:
            slip = _friction(p, normal, dnormal, w, dw, F_N[p], area[p] * stick_slope, mu,
                             h_w, h_gT, h_gp, F_T, g_T, g_p, s, F_trial, e, G, n_G, D, dF_N)
            for k in range(d):
                F_p[k] += F_T[p, k]
            if status[p] != OPEN:
                status[p] = SLIP if slip else STICK
        _element_arrays(p, phi, dphi, dxi, F_p, D, B, f, K)


# ----------------------------------------------------------------------------- public API
def _f64(a) -> np.ndarray:
    """``a`` as a writeable, C-contiguous float64 array (one compiled signature per kernel)."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    return a if a.flags.writeable else a.copy()


def _start(face: FaceType, n: int, xi0: Optional[Array]) -> np.ndarray:
    return np.tile(face.centroid, (n, 1)) if xi0 is None else _f64(np.array(xi0, dtype=float))


def project(face: FaceType, x: Array, coords: Array, xi0: Array | None = None,
            max_iter: int = MAX_ITER, edge_tol: float = EDGE_TOL) -> Projection:
    """Compiled :func:`~dolfinx_friction.contact.projection.project_numpy`."""
    n = len(x)
    xi = _start(face, n, xi0)
    converged, interior = np.empty(n, dtype=bool), np.empty(n, dtype=bool)
    _project_batch(FACE_CODES[face.name], _f64(x), _f64(coords), xi, int(max_iter),
                   float(edge_tol), converged, interior)
    return Projection(xi, interior, converged)


def clearances(face: FaceType, x: Array, coords: Array, slave: np.ndarray, faces: np.ndarray,
               xi0: Array) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Compiled :func:`~dolfinx_friction.contact.projection.clearances_numpy`."""
    n = len(slave)
    xi, outside, g_N = _f64(np.array(xi0, dtype=float)), np.empty(n), np.empty(n)
    _clearance_batch(FACE_CODES[face.name], _f64(x), _f64(coords),
                     np.ascontiguousarray(slave, dtype=np.int64),
                     np.ascontiguousarray(faces, dtype=np.int64), xi, MAX_ITER, outside, g_N)
    return xi, outside, g_N


def face_kinematics(face: FaceType, X_slave: Array, u_slave: Array, X_face: Array,
                    u_face: Array, xi0: Array | None = None,
                    tangent: str = "consistent") -> Kinematics:
    """Compiled :func:`~dolfinx_friction.contact.element.face_kinematics_numpy`."""
    if tangent not in ("consistent", "calculix"):
        raise ValueError(f"unknown tangent option {tangent!r}")
    X_f = _f64(X_face)
    n, nn, d = X_f.shape
    fdim, nodes = face.fdim, nn + 1
    nd = nodes * d
    xi = _start(face, n, xi0)
    converged, interior = np.empty(n, dtype=bool), np.empty(n, dtype=bool)
    normal, g_N, w = np.empty((n, d)), np.empty(n), np.empty((n, d))
    dg_N, phi_e, dphi_e = np.empty((n, nodes, d)), np.empty((n, nodes)), np.empty((n, nodes, fdim))
    dnormal, dw = np.empty((n, d, nodes, d)), np.empty((n, d, nodes, d))
    dxi = np.empty((n, fdim, nodes, d))
    _face_batch(FACE_CODES[face.name], _f64(X_slave), _f64(u_slave), X_f, _f64(u_face), xi,
                tangent == "consistent", MAX_ITER, EDGE_TOL, converged, interior, normal, g_N,
                dg_N.reshape(n, nd), dnormal.reshape(n, d, nd), phi_e, dphi_e,
                dxi.reshape(n, fdim, nd), w, dw.reshape(n, d, nd))
    return Kinematics(normal, g_N, dg_N, dnormal, phi_e, dphi_e, dxi, w, dw, xi,
                      Projection(xi, interior, converged))


def rigid_kinematics(shape: str, X_slave: Array, u_slave: Array, U: Array, *,
                     point: Array | None = None, normal: Array | None = None,
                     center: Array | None = None, axis: Array | None = None,
                     radius: float = 0.0) -> Kinematics:
    """Compiled :func:`~dolfinx_friction.contact.element.rigid_kinematics_numpy`."""
    X_s = _f64(X_slave)
    n, d = X_s.shape
    eye = np.eye(d)
    unit, projector = np.zeros(d), eye
    if shape == "plane":
        unit = unit_vector(normal)
        ref = point
    elif shape == "sphere":
        ref = center
    elif shape == "cylinder":
        a = unit_vector(axis)
        projector, ref = eye - np.outer(a, a), point
    else:
        raise ValueError(f"unknown rigid shape {shape!r}")
    nrm, g_N, w = np.empty((n, d)), np.empty(n), np.empty((n, d))
    dg_N, phi = np.empty((n, 2, d)), np.empty((n, 2))
    dnormal, dw = np.empty((n, d, 2, d)), np.empty((n, d, 2, d))
    _rigid_batch(shape == "plane", X_s, _f64(u_slave), _f64(np.broadcast_to(U, (n, d))),
                 _f64(ref), _f64(projector), _f64(unit), float(radius), nrm, g_N, dg_N,
                 dnormal, phi, w, dw)
    return Kinematics(nrm, g_N, dg_N, dnormal, phi, np.zeros((n, 2, 0)), np.zeros((n, 0, 2, d)),
                      w, dw, np.zeros((n, 0)))


_NO_TABLE = np.zeros(0)


def normal_force(law: Law, g_N: Array, area: Array) -> tuple[np.ndarray, np.ndarray]:
    """Compiled ``law.normal_force(g_N, area)`` for the laws of laws.py (exact types); any
    other law evaluates its own (numpy) method."""
    kind = type(law)
    if kind is Linear:
        code, c, x, y = _LINEAR, np.array([law.K, law.eps]), _NO_TABLE, _NO_TABLE
    elif kind is Exponential:
        code, c, x, y = _EXPONENTIAL, np.array([law.beta, law.p0]), _NO_TABLE, _NO_TABLE
    elif kind is Tabular:
        code, c = _TABULAR, _NO_TABLE
        x, y = np.array(law.overclosures, dtype=float), np.array(law.pressures, dtype=float)
    else:
        return law.normal_force(g_N, area)
    g_N = _f64(g_N)
    F, dF = np.empty(len(g_N)), np.empty(len(g_N))
    _normal_force_batch(code, c, x, y, g_N, _f64(np.broadcast_to(area, g_N.shape)), F, dF)
    return F, dF


def evaluate(kin: Kinematics, area: Array, params: ContactParameters,
             history: Optional[FrictionState] = None, gap_offset: Array | float = 0.0
             ) -> ElementResult:
    """Compiled :func:`~dolfinx_friction.contact.element.evaluate_numpy`."""
    n, d = kin.normal.shape
    nodes = kin.phi.shape[1]
    nd, fdim = nodes * d, kin.dphi.shape[2]
    area = _f64(area)
    g = _f64(kin.g_N + gap_offset)
    F_N, dF_dg = normal_force(params.law, g, area)
    friction = params.mu > 0.0
    if friction:
        h_w, h_gT, h_gp = _f64(history.w), _f64(history.g_T), _f64(history.g_p)
        g_T, g_p = np.empty((n, d)), np.empty((n, d))
    else:
        h_w = h_gT = h_gp = g_T = g_p = np.zeros((1, d))  # unused
    f, K = np.empty((n, nodes, d)), np.empty((n, nodes, d, nodes, d))
    F_T, status = np.zeros((n, d)), np.empty(n, dtype=np.int64)
    _evaluate_batch(_f64(kin.normal), g, _f64(kin.dg_N).reshape(n, nd),
                    _f64(kin.dnormal).reshape(n, d, nd), _f64(kin.phi), _f64(kin.dphi),
                    _f64(kin.dxi).reshape(n, fdim, nd), _f64(kin.w),
                    _f64(kin.dw).reshape(n, d, nd), _f64(F_N), _f64(dF_dg), area,
                    float(params.mu), float(params.stick_slope), friction, h_w, h_gT, h_gp, f,
                    K.reshape(n, nd, nd), F_T, g_T, g_p, status)
    trial = FrictionState(kin.w.copy(), g_T, g_p) if friction else None
    return ElementResult(f, K, F_N, F_T, kin.g_N, status, trial)
