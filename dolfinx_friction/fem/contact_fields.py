"""Contact states as arrays, with one set of names and status codes.

Status codes: ``-1`` no contact element (a slave node beyond the master's reach; in the
nodal fields also every node that is no slave node), ``0`` open, ``1`` stick, ``2`` slip
(:data:`~dolfinx_friction.fem.node_to_surface.NO_ELEMENT` and
:mod:`dolfinx_friction.contact.element`'s ``OPEN``, ``STICK``, ``SLIP``).

Two views of the :class:`~dolfinx_friction.fem.node_to_surface.ContactState` of the
pairs, used by the result files, the pictures and the comparisons with references:

* :func:`nodal_fields`: per node of a body, the fields of the XDMF files —
  ``contact_pressure`` (n, 1) [force / area], > 0 in compression; ``tangential_traction``
  (n, gdim) [force / area], the friction traction acting on the slave body
  (``-tangential_force / area``); ``slip`` (n, 1) [length], accumulated; ``status`` (n, 1).
  Nodes without an element: 0, status -1.
* :func:`slave_rows`: per slave node with an element, the state's own names, as
  ``contact.csv`` has them — ``X`` (n, gdim) reference coordinates [length], ``gap``
  [length] (< 0: overclosure), ``pressure`` [force / area], ``normal_force`` [force],
  ``tangential_force`` (n, gdim) [force] of the slave node on the master, ``slip``
  [length], ``status``, ``area`` [length^2 in 3D, length x thickness in 2D; the revolved
  area on an axisymmetric body, whose forces are per full revolution].
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from dolfinx_friction.fem.node_to_surface import NO_ELEMENT

if TYPE_CHECKING:
    from dolfinx_friction.fem.node_to_surface import ContactState

__all__ = ["SLAVE_COLUMNS", "nodal_fields", "slave_rows"]

#: The per-node values of :func:`slave_rows`, in the order of ``contact.csv``'s columns.
SLAVE_COLUMNS = ("X", "gap", "pressure", "normal_force", "tangential_force", "slip", "status")


def nodal_fields(states: Sequence["ContactState"], n_nodes: int, gdim: int
                 ) -> dict[str, np.ndarray]:
    """The nodal fields of a body with ``n_nodes`` local nodes, from the states of the
    pairs whose slave surface lies on it (their ``nodes`` index the body's nodes)."""
    out = {"contact_pressure": np.zeros((n_nodes, 1)),
           "tangential_traction": np.zeros((n_nodes, gdim)),
           "slip": np.zeros((n_nodes, 1)), "status": np.full((n_nodes, 1), float(NO_ELEMENT))}
    for st in states:
        s = st.has_element
        nodes = st.nodes[s]
        out["contact_pressure"][nodes, 0] = st.pressure[s]
        out["tangential_traction"][nodes] = st.traction[s]
        out["slip"][nodes, 0] = st.slip[s]
        out["status"][nodes, 0] = st.status[s]
    return out


def slave_rows(state: "ContactState") -> dict[str, np.ndarray]:
    """The :data:`SLAVE_COLUMNS` and ``area`` of the slave nodes with an element."""
    s = state.has_element
    return {name: getattr(state, name)[s] for name in (*SLAVE_COLUMNS, "area")}
