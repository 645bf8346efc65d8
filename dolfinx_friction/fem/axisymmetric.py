"""Axisymmetric bodies: a 2D meridian section of a body of revolution, in UFL.

The section lies in the half plane ``r = x[0] >= 0``, ``z = x[1]``, the axis of revolution
is ``x[0] = 0``.  Integrals over the section are integrals over the whole revolved body
when weighted by :func:`revolution_weight` ``2 pi r``: residuals, reactions and forces of
such a body are per full revolution (2 pi), as are the contact areas of its slave nodes
(:class:`~dolfinx_friction.fem.surfaces.SlaveNodes`).  The hoop component of a gradient is
``w_r / r`` (:func:`axisymmetric_grad`), evaluated at quadrature points only, which lie
off the axis.  Hold the nodes on the axis at ``u_r = 0`` (a bc; without it the hoop
stiffness next to the axis keeps ``u_r`` small, not 0); nothing else is special about them.

A body's residual, e.g. linear elasticity (``lam``, ``mu``: Lamé's constants)::

    w = revolution_weight(V.mesh)
    eps = lambda v: ufl.sym(axisymmetric_grad(v))
    sigma = lam * ufl.tr(eps(u)) * ufl.Identity(3) + 2 * mu * eps(u)
    F = ufl.inner(sigma, eps(v)) * w * ufl.dx

and at finite strain ``F3 = ufl.Identity(3) + axisymmetric_grad(u)``, ``P = dW/dF3``,
``F = ufl.inner(P, axisymmetric_grad(v)) * w * ufl.dx``.
"""
from __future__ import annotations

import math

import numpy as np
import ufl
from mpi4py import MPI

from dolfinx_friction.fem.materials import out_of_plane

__all__ = ["axisymmetric_grad", "revolution_weight"]


def revolution_weight(mesh) -> ufl.core.expr.Expr:
    """``2 pi r`` (``r = x[0]``) on a 2D mesh: the weight of ``dx`` and ``ds`` that makes
    integrals over the meridian section integrals over the revolved body [length]."""
    return 2.0 * math.pi * ufl.SpatialCoordinate(mesh)[0]


def axisymmetric_grad(w) -> ufl.core.expr.Expr:
    """The 3 x 3 gradient in (r, z, theta) of an axisymmetric vector field ``w = (w_r, w_z)``
    on a 2D mesh (no twist): the in-plane gradient and the hoop component
    ``w_r / r`` [1 for a displacement].  ``sym`` of it is the small strain, ``I +`` it the
    deformation gradient (``F_thetatheta = 1 + u_r / r``)."""
    g = ufl.grad(w)
    x = ufl.SpatialCoordinate(w.ufl_function_space().ufl_domain())
    return ufl.as_matrix([[g[0, 0], g[0, 1], 0], [g[1, 0], g[1, 1], 0],
                          [0, 0, w[0] / x[0]]])


def section_weight(field) -> object:
    """The weight of ``dx`` and ``ds`` on a body's mesh (a
    :class:`~dolfinx_friction.fem.numbering.BodyField`): :func:`revolution_weight` for an
    axisymmetric body, its thickness for a plane one, 1 in 3D
    (:func:`~dolfinx_friction.fem.materials.out_of_plane`)."""
    if field.axisymmetric:
        return revolution_weight(field.V.mesh)
    return out_of_plane(field.thickness, field.gdim)


#: Nodes of an axisymmetric section may lie this far (relative to the section's extent)
#: on the wrong side of the axis: round-off of a mesh generator.
AXIS_TOLERANCE = 1e-9


def section_fault(field) -> str:
    """Why a body's mesh is no meridian section ("" if it is): not 2D, or nodes at
    ``r = x < 0`` (beyond :data:`AXIS_TOLERANCE` times its extent).  Collective."""
    if field.gdim != 2:
        return f"an axisymmetric body needs a 2D mesh (a meridian section), this one is " \
               f"{field.gdim}D"
    comm = field.V.mesh.comm
    X = field.X
    low = comm.allreduce(float(X.min(initial=np.inf)), op=MPI.MIN)
    high = comm.allreduce(float(X.max(initial=-np.inf)), op=MPI.MAX)
    r_min = comm.allreduce(float(X[:, 0].min(initial=np.inf)), op=MPI.MIN)
    if r_min < -AXIS_TOLERANCE * (high - low):
        return f"nodes at r = x < 0 (down to x = {r_min:g}): a meridian section lies at " \
               "x >= 0, its axis is x = 0"
    return ""
