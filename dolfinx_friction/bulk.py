"""Small-strain linear elasticity of the bodies: stiffness and load vectors from UFL.

The bulk is linear, so each body's stiffness is assembled once and kept as
COO entries in system numbering; its internal force is a matrix product.
"""
from __future__ import annotations

import numpy as np
import ufl

from dolfinx_friction import compat
from dolfinx_friction.fields import BodyField, DofLayout


def _lame(field: BodyField) -> tuple[float, float]:
    E, nu = field.body.E, field.body.nu
    mu = E / (2.0 * (1.0 + nu))
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    if field.gdim == 2 and field.body.plane == "stress":
        lam = 2.0 * lam * mu / (lam + 2.0 * mu)
    return lam, mu


def _thickness(field: BodyField) -> float:
    return field.body.thickness if field.gdim == 2 else 1.0


def stiffness_form(field: BodyField):
    lam, mu = _lame(field)
    u, v = ufl.TrialFunction(field.V), ufl.TestFunction(field.V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    sigma = lam * ufl.tr(eps(u)) * ufl.Identity(field.gdim) + 2.0 * mu * eps(u)
    return compat.form(_thickness(field) * ufl.inner(sigma, eps(v)) * ufl.dx)


def stiffness_entries(field: BodyField, layout: DofLayout) -> tuple[np.ndarray, ...]:
    """The body's stiffness as COO ``(rows, cols, values)`` in system dof numbering."""
    A = compat.assemble_matrix(stiffness_form(field))
    indptr, cols, values = A.getValuesCSR()
    A.destroy()
    d = field.gdim
    sys_cols = layout.from_block_global(field.block, cols.astype(np.int64) // d) * d + cols % d
    rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
    sys_rows = field.nodes[rows // d] * d + rows % d
    return sys_rows, sys_cols, values


def unit_loads(field: BodyField, group: str) -> np.ndarray:
    """Owned load vectors of unit tractions along each axis and of a unit pressure on a group.

    Loads are linear in their values, so any traction ``t`` and pressure ``p``
    give ``t @ unit[:gdim] + p * unit[gdim]`` without compiling a form per value.
    """
    tags, ids = field.mesh.meshtags(field.gdim - 1, [group])
    ds = ufl.Measure("ds", domain=field.V.mesh, subdomain_data=tags)(ids[group])
    v = ufl.TestFunction(field.V)
    t = _thickness(field)
    owned = field.n_owned * field.gdim
    forms = [t * v[c] * ds for c in range(field.gdim)]
    forms.append(-t * ufl.inner(ufl.FacetNormal(field.V.mesh), v) * ds)
    return np.array([compat.assemble_vector(compat.form(f))[:owned] for f in forms])
