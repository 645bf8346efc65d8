"""One body of a block problem: its compiled residual and Jacobian forms, vector and matrix."""
from __future__ import annotations

from typing import Optional, Sequence

import numpy as np
import ufl

from dolfinx_friction import _compat as compat

__all__ = ["BodyForms", "is_linear"]


#: :func:`is_linear`'s answers by the Jacobian's signature and ``u``'s place among its
#: coefficients (the signature numbers them in that order): expanding the derivative of a
#: Neo-Hookean Jacobian takes ~40 ms, a tenth of a 1k-dof run (the form's compilation
#: computes the signature anyway)
_LINEAR: dict = {}


def is_linear(jacobian: ufl.Form, u) -> bool:
    """Whether a Jacobian form does not depend on ``u`` (its body is linear)."""
    from ufl.algorithms import expand_derivatives
    coefficients = jacobian.coefficients()
    if u not in coefficients:
        return True
    key = (jacobian.signature(), coefficients.index(u))
    if key not in _LINEAR:
        _LINEAR[key] = not expand_derivatives(ufl.derivative(jacobian, u)).integrals()
    return _LINEAR[key]


class BodyForms:
    """One block: compiled residual and Jacobian forms, its own vector and matrix (block
    AIJ for a body that is not linear: dolfinx inserts its dense nodal blocks in 0.6x the
    time of AIJ's, and its values are read in the same CSR order)."""

    def __init__(self, F: ufl.Form, u, J: Optional[ufl.Form], bcs: Sequence):
        V = u.function_space
        J = J if J is not None else ufl.derivative(F, u)
        self.u, self.V, self.bcs = u, V, list(bcs)
        self.linear = is_linear(J, u)
        #: linear and zero at u = 0: its residual is the product of its Jacobian with u
        self.homogeneous = self.linear and not ufl.replace(
            F, {u: ufl.zero(*u.ufl_shape)}).integrals()
        self.F, self.J = compat.form(F), compat.form(J)
        self.b = compat.create_vector(self.F)
        self.A = compat.create_matrix(self.J, blocked=not self.linear)
        self.n_owned = V.dofmap.index_map.size_local * V.dofmap.index_map_bs

    def residual(self) -> np.ndarray:
        """Owned values of ``F(u)`` (ghost contributions summed)."""
        with self.b.localForm() as local:
            local.set(0.0)
        compat.assemble_vector_into(self.b, self.F)
        return self.b.getArray(readonly=True)[: self.n_owned]

    def jacobian_values(self) -> np.ndarray:
        """CSR values of the body's Jacobian at its current ``u`` (no bcs)."""
        self.A.zeroEntries()
        compat.assemble_matrix_into(self.A, self.J)
        return self.A.getValuesCSR()[2]
