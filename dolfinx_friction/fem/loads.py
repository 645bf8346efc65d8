"""External loads on the bodies: tractions and pressures as load vectors from UFL."""
from __future__ import annotations

import numpy as np
import ufl

from dolfinx_friction import _compat as compat
from dolfinx_friction.fem.axisymmetric import section_weight
from dolfinx_friction.fem.numbering import BodyField


def unit_loads(field: BodyField, group: str) -> np.ndarray:
    """Owned load vectors of unit tractions along each axis and of a unit pressure on a group,
    (gdim + 1, n_owned dofs) [force; per full revolution on an axisymmetric body]: the
    facets weighted by :func:`~.axisymmetric.section_weight`.

    Loads are linear in their values, so any traction ``t`` and pressure ``p``
    give ``t @ unit[:gdim] + p * unit[gdim]`` without compiling a form per value.
    """
    tags, ids = field.mesh.meshtags(field.gdim - 1, [group])
    ds = ufl.Measure("ds", domain=field.V.mesh, subdomain_data=tags)(ids[group])
    v = ufl.TestFunction(field.V)
    t = section_weight(field)
    owned = field.n_owned * field.gdim
    forms = [t * v[c] * ds for c in range(field.gdim)]
    forms.append(-t * ufl.inner(ufl.FacetNormal(field.V.mesh), v) * ds)
    return np.array([compat.assemble_vector(compat.form(f))[:owned] for f in forms])
