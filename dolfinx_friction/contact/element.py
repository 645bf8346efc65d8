"""The node-to-surface contact element, batched over pairs (docs/theory.md §3-§7).

An element couples one slave node ``p`` with the nodes of one master: the
``nn`` nodes of a master face, or the single reference node of a rigid
obstacle (its translation).  Element nodes are ordered ``[master..., slave]``.

Arrays carry the pair index first.  A derivative ``da/du_i`` of a vector is
stored as ``(n, gdim, nodes, gdim)``, i.e. ``[pair, component k, node i,
component l]``; of a scalar as ``(n, nodes, gdim)``.

Two stages:

* :func:`face_kinematics` / :func:`rigid_kinematics`: projection, normal,
  clearance, relative displacement ``w`` and all their derivatives;
* :func:`evaluate`: normal law, radial return, element forces and the tangent
  (``f_k = -phi_k F_p``, ``K_ki = -phi_k D_i - sum_a phi_k,a F_p (x) dxi^a/du_i``).

Each public function runs the compiled kernel of :mod:`~dolfinx_friction.contact.kernels`
or its numpy reference (``*_numpy``, batched over pairs), as
:mod:`~dolfinx_friction.contact.backend` selects; both give the same results to round-off.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from dolfinx_friction.contact import backend
from dolfinx_friction.contact.friction import FrictionState, radial_return, tangent
from dolfinx_friction.contact.laws import Law
from dolfinx_friction.contact.projection import Projection, project_numpy
from dolfinx_friction.contact.shapes import Array, FaceType, surface_vector, unit_vector

OPEN, STICK, SLIP = 0, 1, 2
STATUS_NAMES = ("open", "stick", "slip")


@dataclass(frozen=True)
class ContactParameters:
    """Normal law, Coulomb coefficient, stick slope ``lambda`` and tangent option."""

    law: Law
    mu: float = 0.0
    stick_slope: float = 0.0
    tangent: str = "consistent"  # "consistent" (option (b)) or "calculix" (option (a))


@dataclass
class Kinematics:
    """Geometry of a batch of contact elements and its derivatives."""

    normal: Array  # (n, d)
    g_N: Array  # (n,)
    dg_N: Array  # (n, nodes, d)
    dnormal: Array  # (n, d, nodes, d)
    phi: Array  # (n, nodes): master weights, -1 for the slave node
    dphi: Array  # (n, nodes, fdim): parametric derivatives, 0 for the slave node
    dxi: Array  # (n, fdim, nodes, d): projection sensitivities
    w: Array  # (n, d): slave minus master displacement at the projection
    dw: Array  # (n, d, nodes, d): derivative of w (option (a) or (b))
    xi: Array  # (n, fdim)
    projection: Optional[Projection] = None

    @property
    def n_nodes(self) -> int:
        return self.phi.shape[1]


def _skew(a: Array) -> Array:
    z = np.zeros(len(a))
    return np.stack([np.stack([z, -a[:, 2], a[:, 1]], -1),
                     np.stack([a[:, 2], z, -a[:, 0]], -1),
                     np.stack([-a[:, 1], a[:, 0], z], -1)], axis=1)


def face_kinematics(face: FaceType, X_slave: Array, u_slave: Array, X_face: Array,
                    u_face: Array, xi0: Array | None = None,
                    tangent: str = "consistent") -> Kinematics:
    """Kinematics of slave nodes against master faces (§3.2-§3.6, §5.2-§5.4).

    ``X_slave, u_slave``: (n, d); ``X_face, u_face``: (n, nn, d); ``xi0`` (n, fdim): a
    start for the projection (default: the face centroid).
    """
    kernels = backend.compiled()
    impl = face_kinematics_numpy if kernels is None else kernels.face_kinematics
    return impl(face, X_slave, u_slave, X_face, u_face, xi0, tangent)


def face_kinematics_numpy(face: FaceType, X_slave: Array, u_slave: Array, X_face: Array,
                          u_face: Array, xi0: Array | None = None,
                          tangent: str = "consistent") -> Kinematics:
    """:func:`face_kinematics` in numpy (the reference)."""
    x_face = X_face + u_face
    proj = project_numpy(face, X_slave + u_slave, x_face, xi0)
    xi = proj.xi
    n, nn, d = x_face.shape
    fdim = face.fdim
    phi, dphi, d2phi = face.evaluate(xi)
    qa = np.einsum("nka,nkd->nad", dphi, x_face)
    qab = np.einsum("nkab,nkd->nabd", d2phi, x_face)
    r = X_slave + u_slave - np.einsum("nk,nkd->nd", phi, x_face)
    m = surface_vector(qa)
    m_norm = np.linalg.norm(m, axis=1)
    normal = m / m_norm[:, None]

    phi_e = np.concatenate([phi, -np.ones((n, 1))], axis=1)
    dphi_e = np.concatenate([dphi, np.zeros((n, 1, fdim))], axis=1)
    eye = np.eye(d)

    # projection sensitivities (§3.5): a dxi/du_i = b_i
    a = -np.einsum("nad,nbd->nab", qa, qa) + np.einsum("nd,nabd->nab", r, qab)
    b = (phi_e[:, None, :, None] * qa[:, :, None, :]
         - np.transpose(dphi_e, (0, 2, 1))[..., None] * r[:, None, None, :])
    dxi = np.linalg.solve(a, b.reshape(n, fdim, (nn + 1) * d)).reshape(n, fdim, nn + 1, d)

    # gap vector, surface vector, normal, clearance (§3.6)
    moving_point = np.einsum("nak,nail->nkil", qa, dxi)
    dr = -phi_e[:, None, :, None] * eye[None, :, None, :] - moving_point
    if fdim == 2:
        dm_dxi = np.stack([np.cross(qab[:, 0, 0], qa[:, 1]) + np.cross(qa[:, 0], qab[:, 0, 1]),
                           np.cross(qab[:, 0, 1], qa[:, 1]) + np.cross(qa[:, 0], qab[:, 1, 1])],
                          axis=1)
        M = np.stack([-_skew(qa[:, 1]), _skew(qa[:, 0])], axis=1)  # dm/dq_,a
    else:
        R = np.array([[0.0, 1.0], [-1.0, 0.0]])
        dm_dxi = np.einsum("kl,nl->nk", R, qab[:, 0, 0])[:, None]
        M = np.broadcast_to(R, (n, 1, 2, 2))
    dm = (np.einsum("nak,nail->nkil", dm_dxi, dxi)
          + np.einsum("nia,nakl->nkil", dphi_e, M))
    P = eye - normal[:, :, None] * normal[:, None, :]
    dnormal = np.einsum("nkc,ncil->nkil", P, dm) / m_norm[:, None, None, None]
    g_N = np.einsum("nd,nd->n", r, normal)
    dg_N = np.einsum("nk,nkil->nil", normal, dr) + np.einsum("nk,nkil->nil", r, dnormal)

    # relative displacement w and its derivative (§5.2, §5.4)
    u_e = np.concatenate([u_face, u_slave[:, None]], axis=1)
    w = -np.einsum("nk,nkd->nd", phi_e, u_e)
    dw = -phi_e[:, None, :, None] * eye[None, :, None, :]
    if tangent == "consistent":
        du_master = np.einsum("nka,nkd->nad", dphi, u_face)
        dw = dw - np.einsum("nak,nail->nkil", du_master, dxi)
    elif tangent != "calculix":
        raise ValueError(f"unknown tangent option {tangent!r}")
    return Kinematics(normal, g_N, dg_N, dnormal, phi_e, dphi_e, dxi, w, dw, xi, proj)


def rigid_kinematics(shape: str, X_slave: Array, u_slave: Array, U: Array, *,
                     point: Array | None = None, normal: Array | None = None,
                     center: Array | None = None, axis: Array | None = None,
                     radius: float = 0.0) -> Kinematics:
    """Kinematics of slave nodes against an analytic rigid obstacle translated by ``U`` (d,).

    The element's master node is the obstacle's reference point, whose
    displacement is ``U``: ``w = u_p - U`` exactly, so options (a) and (b) agree.
    ``shape``: "plane" (``point``, ``normal``), "sphere" (``center``, ``radius``; a circle
    in 2D) or "cylinder" (``point``, ``axis``, ``radius``).
    """
    kernels = backend.compiled()
    impl = rigid_kinematics_numpy if kernels is None else kernels.rigid_kinematics
    return impl(shape, X_slave, u_slave, U, point=point, normal=normal, center=center,
                axis=axis, radius=radius)


def rigid_kinematics_numpy(shape: str, X_slave: Array, u_slave: Array, U: Array, *,
                           point: Array | None = None, normal: Array | None = None,
                           center: Array | None = None, axis: Array | None = None,
                           radius: float = 0.0) -> Kinematics:
    """:func:`rigid_kinematics` in numpy (the reference)."""
    x = X_slave + u_slave
    n, d = x.shape
    eye = np.eye(d)
    if shape == "plane":
        unit = unit_vector(normal)
        nrm = np.broadcast_to(unit, (n, d)).copy()
        g_N = (x - (np.asarray(point, float) + U)) @ unit
        dn_slave = np.zeros((n, d, d))
    else:
        v = x - (np.asarray(center if shape == "sphere" else point, float) + U)
        proj = eye.copy()
        if shape == "cylinder":
            a = unit_vector(axis)
            proj = eye - np.outer(a, a)
            v = v @ proj
        elif shape != "sphere":
            raise ValueError(f"unknown rigid shape {shape!r}")
        rho = np.linalg.norm(v, axis=1)
        nrm = v / rho[:, None]
        g_N = rho - radius
        dn_slave = (proj - nrm[:, :, None] * nrm[:, None, :]) / rho[:, None, None]
    dnormal = np.stack([-dn_slave, dn_slave], axis=2)
    dg_N = np.stack([-nrm, nrm], axis=1)
    phi = np.tile([1.0, -1.0], (n, 1))
    dw = -phi[:, None, :, None] * eye[None, :, None, :]
    return Kinematics(nrm, g_N, dg_N, dnormal, phi, np.zeros((n, 2, 0)),
                      np.zeros((n, 0, 2, d)), u_slave - U, dw, np.zeros((n, 0)))


def sdf_kinematics(X_slave: Array, u_slave: Array, U: Array, distance, gradient, hessian,
                   Q: Array | None = None, pivot: Array | None = None) -> Kinematics:
    """Kinematics of slave nodes against a rigid obstacle given by a signed distance
    ``distance(y)`` (n, d) -> (n,) (> 0 outside, towards the body), its ``gradient(y)``
    (n, d) and ``hessian(y)`` (n, d, d), in the obstacle's reference frame, turned by ``Q``
    (d, d) about ``pivot`` (d,) and translated by ``U`` (d,).

    The clearance is ``g_N = distance(y)`` at ``y = Q^T (x_p - pivot - U) + pivot``, the normal
    the turned unit gradient; ``w = u_p - U`` as for the analytic shapes.  Numpy only.
    """
    x = X_slave + u_slave
    n, d = x.shape
    Q = np.eye(d) if Q is None else np.asarray(Q, float)
    c = np.zeros(d) if pivot is None else np.asarray(pivot, float)
    y = (x - c - U) @ Q + c  # rows: Q^T (x - c - U) + c
    g_N = np.asarray(distance(y), float).reshape(n)
    grad = np.asarray(gradient(y), float).reshape(n, d) @ Q.T  # turned: Q grad
    H = np.einsum("ij,njk,lk->nil", Q, np.asarray(hessian(y), float).reshape(n, d, d), Q)
    size = np.linalg.norm(grad, axis=1)
    nrm = grad / size[:, None]
    P = np.eye(d) - nrm[:, :, None] * nrm[:, None, :]
    dn_slave = np.einsum("nij,njk->nik", P, H) / size[:, None, None]
    eye = np.eye(d)
    phi = np.tile([1.0, -1.0], (n, 1))
    return Kinematics(nrm, g_N, np.stack([-grad, grad], axis=1),
                      np.stack([-dn_slave, dn_slave], axis=2), phi, np.zeros((n, 2, 0)),
                      np.zeros((n, 0, 2, d)), u_slave - U,
                      -phi[:, None, :, None] * eye[None, :, None, :], np.zeros((n, 0)))


@dataclass
class ElementResult:
    """Forces, tangents and contact state of a batch of elements."""

    f: Array  # (n, nodes, d) internal forces, master nodes first, slave last
    K: Array  # (n, nodes, d, nodes, d) tangent df_k/du_i
    F_N: Array  # (n,) normal force (> 0 in compression)
    F_T: Array  # (n, d) tangential force of the slave on the master
    g_N: Array  # (n,) clearance (before any offset)
    status: np.ndarray  # (n,) OPEN, STICK or SLIP
    trial: Optional[FrictionState]  # trial history; None when mu = 0


def evaluate(kin: Kinematics, area: Array, params: ContactParameters,
             history: Optional[FrictionState] = None, gap_offset: Array | float = 0.0
             ) -> ElementResult:
    """Element forces and consistent tangent for a batch of elements.

    ``area``: representative slave areas ``A_p`` (n,); ``history``: converged
    ``(w_n, g_T_n, g_p_n)`` per element (required when ``mu > 0``);
    ``gap_offset``: the initial-overclosure ramp shift of §3.4, added to ``g_N``
    before the law is evaluated.
    """
    kernels = backend.compiled()
    impl = evaluate_numpy if kernels is None else kernels.evaluate
    return impl(kin, area, params, history, gap_offset)


def evaluate_numpy(kin: Kinematics, area: Array, params: ContactParameters,
                   history: Optional[FrictionState] = None, gap_offset: Array | float = 0.0
                   ) -> ElementResult:
    """:func:`evaluate` in numpy (the reference)."""
    n, d = kin.normal.shape
    nrm = kin.normal
    F_N, dF_N_dg = params.law.normal_force(kin.g_N + gap_offset, area)
    dF_N = dF_N_dg[:, None, None] * kin.dg_N
    F_p = -F_N[:, None] * nrm
    D = -nrm[:, :, None, None] * dF_N[:, None] - F_N[:, None, None, None] * kin.dnormal
    status = np.where(kin.g_N + gap_offset > 0.0, OPEN, SLIP)
    F_T = np.zeros((n, d))
    trial = None
    if params.mu > 0.0:
        K_t = params.stick_slope * area
        s = kin.w - history.w
        s_N = np.einsum("nd,nd->n", s, nrm)
        g_T = history.g_T + s - s_N[:, None] * nrm
        G = (np.einsum("nkc,ncil->nkil", np.eye(d) - nrm[:, :, None] * nrm[:, None, :], kin.dw)
             - nrm[:, :, None, None] * np.einsum("nc,ncil->nil", s, kin.dnormal)[:, None]
             - s_N[:, None, None, None] * kin.dnormal)
        rm = radial_return(g_T, history.g_p, K_t, params.mu, F_N)
        F_T = rm.F_T
        F_p = F_p + F_T
        D = D + tangent(rm, K_t, params.mu, F_N, G, dF_N)
        status = np.where(status == OPEN, OPEN, np.where(rm.slip, SLIP, STICK))
        trial = FrictionState(kin.w.copy(), g_T, rm.g_p)
    f = -kin.phi[:, :, None] * F_p[:, None, :]
    K = (-np.einsum("nk,ncil->nkcil", kin.phi, D)
         - np.einsum("nka,nc,nail->nkcil", kin.dphi, F_p, kin.dxi))
    return ElementResult(f, K, F_N, F_T, kin.g_N, status, trial)
