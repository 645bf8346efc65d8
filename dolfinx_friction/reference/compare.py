"""Contact results gathered for comparison with reference solutions."""
from __future__ import annotations

import numpy as np

from dolfinx_friction.fem.contact_fields import slave_rows


def contact_state(result, pair: int = 0) -> dict[str, np.ndarray]:
    """The slave nodes with an element in contact pair ``pair`` (its index in the scene;
    current increment), gathered on every rank: the arrays of
    :func:`~dolfinx_friction.fem.contact_fields.slave_rows` (``X``, ``gap``, ``pressure``,
    ``normal_force``, ``tangential_force``, ``slip``, ``status``, ``area``), and ``X_all``,
    the reference coordinates of every slave node of the pair.
    """
    problem = result.problem
    st = problem.pair_of(problem.scene.contacts[pair]).state()
    comm = problem.comm
    parts = comm.allgather(slave_rows(st))
    out = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    out["X_all"] = np.concatenate(comm.allgather(st.X))
    return out


def stick_half_width(x: np.ndarray, status: np.ndarray) -> tuple[float, float, float]:
    """Half-width, centre and node spacing of the stick zone along ``x``.

    The zone's edges lie midway between the outermost sticking nodes and their slipping
    neighbours; ``status`` in the codes of :mod:`~dolfinx_friction.fem.contact_fields`.
    """
    order = np.argsort(x)
    x, status = x[order], status[order]
    stick = np.flatnonzero(status == 1)
    lo, hi = stick.min(), stick.max()
    left = 0.5 * (x[lo] + x[lo - 1]) if lo > 0 else x[lo]
    right = 0.5 * (x[hi] + x[hi + 1]) if hi + 1 < len(x) else x[hi]
    return 0.5 * (right - left), 0.5 * (right + left), float(np.median(np.diff(x)))
