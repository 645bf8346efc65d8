"""Rolling contact: a rigid wheel rolls freely, then is driven with creep, on an elastic layer.

A rigid circle (radius R = 1) is pressed 0.003 into a layer [0, 4] x [-1, 0] (plane strain,
E = 1000, nu = 0.49, P2 triangles of size 0.01 along the track, mu = 0.3), rolled freely by
0.5 along x (turned by -0.5 rad: the wheel's point at the contact stands still), then driven
by 1.0 turning 0.6 % faster (creep xi = 0.006, about half of the saturation creep).

Reference (Carter 1926, Johnson §8.3; :func:`dolfinx_friction.reference.analytic.
carter_creep_force`): the tangential force of steady tractive rolling is
``F_t / (mu F_n) = 1 - (1 - xi/xi_sat)^2`` with ``xi_sat = mu a / R``, ``a`` the Hertz
half-width of the normal force with ``1/E* = (1 - nu^2)/E``.  It holds where normal pressure
moves no surface point tangentially (Dundurs' beta = 0), here nearly: beta =
(1 - 2 nu)/(2 (1 - nu)) = 0.02 for a rigid wheel on the nu = 0.49 layer.  Rolling freely the
wheel carries almost no tangential force.  The picture shows the stick zone at the leading
edge of the contact.

    python demos/rolling_cylinder.py
    python -m dolfinx_friction run demos/rolling_cylinder.toml
"""
from __future__ import annotations

from pathlib import Path

import _common as C  # noqa: F401  (pyvista before dolfinx)
import numpy as np
from mpi4py import MPI

from dolfinx_friction.reference import meshes
from dolfinx_friction.reference.analytic import (carter_creep_force, carter_saturation_creep,
                                                 effective_modulus, hertz_line)

SCENE = C.HERE / "rolling_cylinder.toml"
MESH = C.HERE / "rolling_cylinder.msh"
R, E, NU, MU, CREEP = 1.0, 1000.0, 0.49, 0.3, 0.006


def build_mesh(path: Path, h_track: float = 0.01, h_far: float = 0.2) -> None:
    """The layer [0, 4] x [-1, 0], P2 triangles of size ``h_track`` along the wheel's track
    (x from 0.75 to 2.75), ``h_far`` away from it."""
    meshes.rolling_layer(Path(path), width=4.0, depth=1.0, track=(0.75, 2.75),
                         h_track=h_track, h_far=h_far, order=2, comm=MPI.COMM_SELF)


def main(argv=None) -> None:
    args, scene = C.command_line(__doc__, SCENE, argv)
    result = C.run_demo(args, scene, MESH, build_mesh)
    if not args.no_render:
        C.render_status_and_pressure(result, "rolling_cylinder", warp=20.0,
                                     title="rigid wheel driven with creep 0.006 (mu = 0.3)")
    C.root_print("step   inc  slipping/active   F_t/F_n     M_z/(R F_t)")
    rows = []
    for inc in result.increments:
        F, M = inc.rigid_f["wheel"], inc.rigid_m["wheel"][0]
        ratio = F[0] / -F[1]
        rows.append((inc.t, ratio / MU))
        C.root_print(f"{C.increment_line(inc)}   {ratio:+.5f}   "
                     f"{M / (R * F[0]) if F[0] else 0.0:.5f}")
    F = result.increments[-1].rigid_f["wheel"]
    a = hertz_line(-F[1], R, effective_modulus(E, NU)).a
    carter = carter_creep_force(CREEP, MU, a, R)
    got = -F[0] / (MU * -F[1])
    C.root_print(f"driven: F_t/(mu F_n) = {got:.4f}, Carter {carter:.4f} ({C.relerr(got, carter)}) "
                 f"at xi/xi_sat = {CREEP / carter_saturation_creep(MU, a, R):.3f}, a = {a:.4f}")
    if not args.no_render and result.problem.comm.rank == 0:
        plt = C.pyplot()
        fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=120)
        t, r = np.array(rows).T
        ax.plot(t, -r, "o-", ms=3, label="computed")
        ax.axhline(carter, color="k", ls="--", label=f"Carter, xi/xi_sat = "
                   f"{CREEP / carter_saturation_creep(MU, a, R):.2f}")
        ax.set_xlabel("pseudo-time (press, free roll over 0.5, drive over 1.0)")
        ax.set_ylabel("F_t / (mu F_n)")
        ax.set_title("rigid wheel on a nu = 0.49 layer: free rolling, then creep 0.006",
                     fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        C.save_figure(fig, result, "rolling_cylinder_force")


if __name__ == "__main__":
    main()
