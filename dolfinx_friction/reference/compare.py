"""Contact results gathered for comparison with reference solutions."""
from __future__ import annotations

import numpy as np


def contact_state(result, pair: int = 0) -> dict[str, np.ndarray]:
    """Reference coordinates, pressure, forces, gap and status of the slave nodes with an
    element in contact pair ``pair`` (its index in the scene; current increment), gathered
    on every rank.

    ``X_all`` holds the reference coordinates of every slave node of the pair.
    """
    problem = result.problem
    st = problem.pair_of(problem.scene.contacts[pair]).state()
    s = st.has_element
    local = dict(X=st.X[s], pressure=st.pressure[s], F_N=st.normal_force[s],
                 F_T=st.tangential_force[s], area=st.area[s], status=st.status[s],
                 g_N=st.gap[s])
    comm = problem.comm
    parts = comm.allgather(local)
    out = {k: np.concatenate([p[k] for p in parts]) for k in local}
    out["X_all"] = np.concatenate(comm.allgather(st.X))
    return out


def stick_half_width(x: np.ndarray, status: np.ndarray) -> tuple[float, float, float]:
    """Half-width, centre and node spacing of the stick zone along ``x``.

    The zone's edges lie midway between the outermost sticking nodes and their slipping
    neighbours; ``status`` uses the element codes (1 stick, 2 slip).
    """
    order = np.argsort(x)
    x, status = x[order], status[order]
    stick = np.flatnonzero(status == 1)
    lo, hi = stick.min(), stick.max()
    left = 0.5 * (x[lo] + x[lo - 1]) if lo > 0 else x[lo]
    right = 0.5 * (x[hi] + x[hi + 1]) if hi + 1 < len(x) else x[hi]
    return 0.5 * (right - left), 0.5 * (right + left), float(np.median(np.diff(x)))
