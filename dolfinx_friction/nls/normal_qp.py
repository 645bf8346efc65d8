"""The normal contact of a Newton step solved exactly: a convex quadratic program in the
elements' normal forces (frictionless pairs, bilinear law, linear bodies).

With the normals and projections frozen at the iterate, element ``i``'s overclosure is
affine in the step, ``d_i + a_i . du``, and its force ``F_i = k_i max(d_i + a_i . du, 0)
- s_i`` (:class:`~dolfinx_friction.fem.node_to_surface.NormalModel`).  With ``K`` the
bodies' stiffness and ``r_b = r - A^T (F + s)`` the residual without the contact forces,
the step ``du = -K^-1 (r_b + A^T lam)`` balances ``lam = k max(d - A K^-1 r_b - W lam, 0)``,
``W = A K^-1 A^T``: the complementarity problem of the strictly convex program

    min 1/2 lam^T (W + diag(1/k)) lam - q^T lam,   lam >= 0,   q = d - A K^-1 r_b,

whose unique minimiser an active-set method (Lawson and Hanson's NNLS on the Cholesky
factor) finds in finitely many steps without cycling, where Newton's step on the
linearised law flips the statuses of the nodes at the edge of a growing zone back and
forth (docs/theory.md §10.3).  No PETSc here: :class:`~dolfinx_friction.nls.linear.Condensed`
supplies ``K^-1`` on the contact dofs.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.sparse

__all__ = ["Elements", "gather", "normal_forces"]


@dataclass
class Elements:
    """Every rank's elements of every pair, in rank order: ``A`` (n, len(dofs)) the
    overclosures' gradients on the global ``dofs`` they touch (sorted), zero on the
    constrained ones; ``d``, ``force``, ``k``, ``s``, ``width``, ``closed`` (n,) as in the
    models."""

    dofs: np.ndarray
    A: scipy.sparse.csr_matrix
    d: np.ndarray
    force: np.ndarray
    k: np.ndarray
    s: np.ndarray
    width: np.ndarray
    closed: np.ndarray

    def changes(self, lam: np.ndarray, d_new: np.ndarray) -> bool:
        """Whether the forces ``lam`` (their overclosures ``d_new``) close or open an
        element decisively: both overclosures, now and then, at least ``width`` from 0
        (within it the law is smooth, and Newton's own step has its tangent)."""
        decisive = (np.abs(self.d) >= self.width) & (np.abs(d_new) >= self.width)
        return bool(((lam > 0.0) != self.closed)[decisive].any())


def gather(comm, models: list, fixed: np.ndarray) -> Elements:
    """All ranks' ``models`` (each rank's list of
    :class:`~dolfinx_friction.fem.node_to_surface.NormalModel`) joined on every rank, in
    rank order (collective); ``fixed``: the constrained global dofs (sorted)."""
    def flat(m) -> tuple:
        rows = np.broadcast_to(np.arange(len(m.d))[:, None], m.dofs.shape)
        return (rows.ravel(), m.dofs.ravel(), m.a.ravel(), m.d, m.force, m.k, m.s, m.width,
                m.closed)

    parts = [flat(m) for m in models]
    mine = []
    for j in range(9):
        pieces = [p[j] + sum(len(q[3]) for q in parts[:i]) if j == 0 else p[j]
                  for i, p in enumerate(parts)]
        mine.append(np.concatenate(pieces) if pieces else np.zeros(0))
    ranks = comm.allgather(mine) if comm.size > 1 else [mine]
    offsets = np.cumsum([0] + [len(r[3]) for r in ranks])
    rows, dofs, a, d, force, k, s, width, closed = (
        np.concatenate([r[j] + (offsets[i] if j == 0 else 0) for i, r in enumerate(ranks)])
        for j in range(9))
    held = dofs < 0
    if len(fixed):
        held |= fixed[np.searchsorted(fixed, dofs).clip(max=len(fixed) - 1)] == dofs
    keep = ~held & (a != 0.0)
    used = np.unique(dofs[keep])
    indptr = np.concatenate([[0], np.cumsum(np.bincount(rows[keep].astype(np.int64),
                                                        minlength=len(d)))])
    A = scipy.sparse.csr_matrix((a[keep], np.searchsorted(used, dofs[keep]), indptr),
                                shape=(len(d), len(used)))  # rows in order: CSR as it is
    return Elements(used, A, d, force, k, s, width, closed.astype(bool))


#: the largest ratio of the squared Cholesky pivots of the program's matrix (a lower bound
#: of its condition number) at which its forces are taken: a body that only the contact
#: holds leaves ``K`` singular but for round-off, its rigid motion a direction of ``W``
#: some 1e15 times the others (the patch test's upper block: 2.6e13 against 0.06)
CONDITION = 1e12


def normal_forces(W: np.ndarray, k: np.ndarray, q: np.ndarray) -> Optional[np.ndarray]:
    """``lam >= 0`` minimising ``1/2 lam^T (W + diag(1/k)) lam - q^T lam`` (``W``
    symmetric positive semi-definite, ``k > 0``): NNLS on ``M = L L^T``, as
    ``min |L^T lam - L^-1 q|`` over ``lam >= 0``; None where ``M`` is not numerically
    positive definite (:data:`CONDITION`)."""
    if not len(q):
        return np.zeros(0)
    try:  # (non-finite entries: ValueError)
        with np.errstate(divide="ignore"):
            L = scipy.linalg.cholesky(0.5 * (W + W.T) + np.diag(1.0 / k), lower=True)
    except (np.linalg.LinAlgError, ValueError):
        return None
    pivots = np.diag(L) ** 2
    if not pivots.max() <= CONDITION * pivots.min():
        return None
    rhs = scipy.linalg.solve_triangular(L, q, lower=True)
    lam, _ = scipy.optimize.nnls(L.T, rhs, maxiter=max(50 * len(q), 100))
    return lam
