"""External loads on the bodies: tractions and pressures as load vectors from UFL."""
from __future__ import annotations

import numpy as np
import ufl

from dolfinx_friction import _compat as compat
from dolfinx_friction.fem.numbering import BodyField


def unit_loads(field: BodyField, group: str, thickness: float) -> np.ndarray:
    """Owned load vectors of unit tractions along each axis and of a unit pressure on a group,
    (gdim + 1, n_owned dofs) [force]; ``thickness``: :func:`~.materials.out_of_plane`'s.

    Loads are linear in their values, so any traction ``t`` and pressure ``p``
    give ``t @ unit[:gdim] + p * unit[gdim]`` without compiling a form per value.
    """
    tags, ids = field.mesh.meshtags(field.gdim - 1, [group])
    ds = ufl.Measure("ds", domain=field.V.mesh, subdomain_data=tags)(ids[group])
    v = ufl.TestFunction(field.V)
    t = thickness
    owned = field.n_owned * field.gdim
    forms = [t * v[c] * ds for c in range(field.gdim)]
    forms.append(-t * ufl.inner(ufl.FacetNormal(field.V.mesh), v) * ds)
    return np.array([compat.assemble_vector(compat.form(f))[:owned] for f in forms])
