"""Rigid motions that nothing holds.

A body that frictionless contact alone supports in some direction, or nothing at all, has a
rigid motion that changes no residual: a converged Newton iterate may carry any amount of
it (an arbitrary drift).  :class:`RigidMotions` finds such motions at a converged state.

The rigid motions of every body (translations, and rotations about its centroid scaled by
its size, so that each moves the body's nodes by about 1) and the translations of the
rigid obstacles that are unknowns span a space of a few coordinates ``a``.  What holds the
bodies gives linear rows in ``a``:

* a constrained row (a Dirichlet condition, a prescribed obstacle translation): the motion
  of its node along its component;
* a closed slave node of a contact pair: the relative motion of slave and master there
  along the contact normal (frictionless), or in every direction (with friction);
* a body's own form (a spring, an elastic foundation): ``r^T K r / max |diag K|`` over its
  rigid motions ``r``, with the body's Jacobian ``K`` at set-up (zero for elasticity).

A motion is held where the Gram matrix ``S`` of the rows (summed over ranks; a few dozen
entries a side) has it in its range: the eigenvectors of ``S`` whose eigenvalues are below
:data:`TOL` times the largest are the motions nothing holds.  An obstacle's own free
translation (a frictionless plane moved along itself: the same plane) is harmless and not
reported; a body's share of the others is.
"""
from __future__ import annotations

from typing import Sequence, Union

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

#: eigenvalues of ``S`` below this share of its largest are motions that nothing holds: the
#: round-off of ``S`` is about 1e-16 of its largest eigenvalue, while a motion held only
#: through the tilt of deformed master faces (strains of 1e-3) has about 1e-5 of it
TOL = 1e-10


class RigidMotions:
    """The rigid motions of the bodies (owned node coordinates ``coordinates[k]``
    (n_k, gdim) at set-up, names ``names[k]`` for the messages) and of ``n_obstacles``
    obstacle translations; collective."""

    def __init__(self, comm: MPI.Comm, coordinates: Sequence[np.ndarray], n_obstacles: int,
                 names: Sequence[str]):
        self.comm, self.names = comm, list(names)
        self.gdim = d = coordinates[0].shape[1]
        self.per_body = d + (1 if d == 2 else 3)
        self.n_bodies = len(coordinates)
        self.size = self.n_bodies * self.per_body + n_obstacles * d
        #: the bodies' centroids, the centres of their rotations (:meth:`move`)
        self.centre = self._centroids(coordinates)
        self.length = []  # the bodies' sizes at set-up: their nodes' largest distance from it
        for X, centre in zip(coordinates, self.centre):
            length = comm.allreduce(np.linalg.norm(X - centre, axis=1).max(initial=0.0),
                                    op=MPI.MAX)
            self.length.append(length if length > 0.0 else 1.0)
        #: what the bodies' own forms hold, (size, size), about the centroids at set-up
        self.bulk = np.zeros((self.size, self.size))
        self._bulk_centre = list(self.centre)

    def _centroids(self, coordinates: Sequence[np.ndarray]) -> list[np.ndarray]:
        return [self.comm.allreduce(X.sum(axis=0)) / self.comm.allreduce(len(X))
                for X in coordinates]

    def move(self, coordinates: Sequence[np.ndarray]) -> None:
        """Turn the rotations about the centroids of the bodies' current owned node
        coordinates ``coordinates[k]`` (n_k, gdim): a body carried far from where it was
        set up keeps rotations of about unit size (collective)."""
        self.centre = self._centroids(coordinates)

    def rows(self, owner: Union[int, np.ndarray], x: np.ndarray, e: np.ndarray) -> np.ndarray:
        """(n, size): the motion along ``e`` (n, gdim) of points ``x`` (n, gdim) [length]
        of ``owner``, one for all points or (n,): a body's index, or ``n_bodies + j`` for
        obstacle ``j`` (which only translates)."""
        d, out = self.gdim, np.zeros((len(e), self.size))
        single = np.ndim(owner) == 0
        for k in [owner] if single else np.unique(owner):
            at = slice(None) if single else np.flatnonzero(owner == k)
            if k >= self.n_bodies:
                o = self.n_bodies * self.per_body + (k - self.n_bodies) * d
                out[at, o:o + d] = e[at]
                continue
            o = k * self.per_body
            out[at, o:o + d] = e[at]
            r = (x[at] - self.centre[k]) / self.length[k]
            # e . (axis x r) = axis . (r x e): the rotations' columns are r x e
            turn = (r[:, :1] * e[at, 1:] - r[:, 1:] * e[at, :1] if d == 2
                    else np.cross(r, e[at]))
            out[at, o + d:o + self.per_body] = turn
        return out

    def add_stiffness(self, k: int, K: PETSc.Mat, X: np.ndarray) -> None:
        """What body ``k``'s own Jacobian ``K`` (its space's numbering, owned node
        coordinates ``X`` (n, gdim)) holds: ``r^T K r / max |diag K|`` over its rigid
        motions ``r`` (collective)."""
        d, n = self.gdim, len(X)
        fields = np.stack([self.rows(k, X, np.tile(e, (n, 1)))
                           for e in np.eye(d)], axis=1)  # (n, d, size)
        o = k * self.per_body
        modes = fields[:, :, o:o + self.per_body].reshape(n * d, self.per_body)
        right, left = K.createVecs()
        product = np.zeros((self.per_body, self.per_body))
        for j in range(self.per_body):
            right.setArray(modes[:, j])
            K.mult(right, left)
            product[:, j] = modes.T @ left.getArray(readonly=True)
        diagonal = K.getDiagonal()
        scale = diagonal.norm(PETSc.NormType.NORM_INFINITY)
        for v in (right, left, diagonal):
            v.destroy()
        product = self.comm.allreduce(product)
        if scale > 0.0:
            self.bulk[o:o + self.per_body, o:o + self.per_body] = (product + product.T) / (
                2 * scale)

    def unheld(self, rows: Sequence[np.ndarray]) -> str:
        """One line naming a body and a rigid motion of it that none of ``rows`` (this
        rank's holding rows, each (m, size)) nor the bodies' own forms hold; "" if there is
        none (collective; the same answer on every rank)."""
        S = sum((r.T @ r for r in rows), self._bulk_here())
        S = self.comm.reduce(S, root=0)
        message = self._describe(S) if self.comm.rank == 0 else None
        return self.comm.bcast(message, root=0)

    def _bulk_here(self) -> np.ndarray:
        """:attr:`bulk` in the coordinates of the rotations about the current centres: a
        motion ``(t, w)`` about ``c`` is ``(t + w / L x (c_0 - c), w)`` about ``c_0``."""
        d, T = self.gdim, np.eye(self.size)
        for k in range(self.n_bodies):
            o = k * self.per_body
            delta = (self._bulk_centre[k] - self.centre[k]) / self.length[k]
            if d == 2:
                T[o:o + 2, o + 2] = -delta[1], delta[0]
            else:
                T[o:o + 3, o + 3:o + 6] = [[0.0, delta[2], -delta[1]],
                                           [-delta[2], 0.0, delta[0]],
                                           [delta[1], -delta[0], 0.0]]
        return T.T @ self.bulk @ T

    def _describe(self, S: np.ndarray) -> str:
        if not np.isfinite(S).all():
            return ""  # a state that is not finite fails its own check (stepping._finite)
        w, vectors = np.linalg.eigh(S)
        free = vectors[:, w <= TOL * max(w[-1], 0.0)]
        if not free.shape[1]:
            return ""
        for k in range(self.n_bodies):
            o = k * self.per_body
            share = free[o:o + self.per_body]
            basis, weights, _ = np.linalg.svd(share, full_matrices=False)
            basis = basis[:, weights > 1e-3]  # the body's free motions, orthonormal
            if basis.shape[1]:
                more = basis.shape[1] - 1
                return (f"body {self.names[k]} can move rigidly ({self._motion(k, basis)}) "
                        f"with nothing to hold it (no constraint, no friction, no contact "
                        f"normal resists that motion"
                        + (f"; {more} more such motion{'s' * (more > 1)}" if more else "")
                        + "): the solution may drift along it by any amount; constrain the "
                        "body or give its contact friction")
        return ""

    def _motion(self, k: int, basis: np.ndarray) -> str:
        """A free motion of body ``k`` among the orthonormal ``basis`` (per_body, m): the
        translation nearest to a coordinate axis if there is one, else a rotation."""
        d = self.gdim
        _, weights, right = np.linalg.svd(basis[d:])
        rank = int((weights > 1e-6).sum())
        if rank < basis.shape[1]:  # combinations without rotation: translations
            q, _ = np.linalg.qr(basis[:d] @ right[rank:].T)
            t = q @ q[np.argmax(np.linalg.norm(q, axis=1))]  # an axis projected on them
            return f"translation along {_vector(t, direction=True)}"
        a = basis @ right[0]
        t, omega = a[:d], a[d:] / self.length[k]
        if d == 2:  # about the point that does not move
            return f"rotation about {_vector(self.centre[k] + np.array([-t[1], t[0]]) / omega[0])}"
        norm = np.linalg.norm(omega)
        axis = omega / norm
        point = self.centre[k] + np.cross(omega, t) / norm ** 2
        screw = abs(t @ axis) > 1e-6 * (np.linalg.norm(t) + norm * self.length[k])
        along = " with a translation along it" if screw else ""
        return (f"rotation about the axis {_vector(axis, direction=True)} through "
                f"{_vector(point)}{along}")


def _vector(v: np.ndarray, direction: bool = False) -> str:
    """``(a, b[, c])`` to 3 significant digits; a ``direction`` as a unit vector with its
    largest component positive."""
    v = np.asarray(v, dtype=float)
    if direction:
        v = v / np.linalg.norm(v) * np.sign(v[np.argmax(np.abs(v))])
    scale = np.abs(v).max(initial=0.0)
    v = np.where(np.abs(v) < 1e-6 * scale, 0.0, v)  # round-off of a zero component
    return "(" + ", ".join(f"{c + 0.0:.3g}" for c in v) + ")"
