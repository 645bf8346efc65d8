"""Hertz point contact: the sphere of ``hertz_sphere.toml`` as an axisymmetric section.

The meridian section (r = x, z = y) of the lower half of a sphere (radius R = 10, centre
(0, R)): a quarter disk of triangles, refined around the pole as the 3D demo's eighth of
a sphere (``h_contact`` = 0.12).  Its flat top (z = R) is pushed down by 0.15 in 4
increments onto a rigid plane z = 0; the nodes on the axis keep u_r = 0.  E = 1000,
nu = 0.3, frictionless.  The reaction is per full revolution: the total force F.

Reference (Johnson §4.2, :func:`dolfinx_friction.reference.analytic.hertz_sphere`):
``a = (3 F R / (4 E*))^(1/3)``, ``p0 = 3 F / (2 pi a^2)``, ``1/E* = (1-nu^2)/E``.  The
script prints the nodal pressure on the axis and a fit of ``p^2 = p0^2 (1 - r^2/a^2)``
against Hertz, and plots p(r) and the section.

    python demos/hertz_axisymmetric.py
"""
from __future__ import annotations

from pathlib import Path

import _common as C  # noqa: F401  (pyvista before dolfinx)
import numpy as np

from dolfinx_friction.reference import meshes
from dolfinx_friction.reference.analytic import (effective_modulus, fit_elliptic, hertz_sphere,
                                                 hertz_sphere_pressure)

SCENE = C.HERE / "hertz_axisymmetric.toml"
MESH = C.HERE / "hertz_axisymmetric.msh"
R, E, NU = 10.0, 1000.0, 0.3


def build_mesh(path: Path, h_contact: float = 0.12, h_far: float = 2.0) -> None:
    """The quarter disk (:func:`dolfinx_friction.reference.meshes.sphere_section`):
    triangles of size ``h_contact`` within 1.8 of the pole, ``h_far`` far away."""
    meshes.sphere_section(path, R, h_contact, h_far)


def main(argv=None) -> None:
    args, scene = C.command_line(__doc__, SCENE, argv)
    result = C.run_demo(args, scene, MESH, build_mesh)
    if not args.no_render:
        C.render(result, "hertz_axisymmetric", warp=5.0,
                 title="Hertz: sphere on a rigid plane (meridian section)", contact_margin=0.3)
    st = C.contact_state(result)
    if C.MPI.COMM_WORLD.rank != 0:
        return
    F = abs(result.increments[-1].reactions["sphere_top"][1])
    E_star = effective_modulus(E, NU)
    a, p0, delta = hertz_sphere(F, R, E_star)
    closed = st["status"] != 0
    r, p = st["X"][closed, 0], st["pressure"][closed]
    order = np.argsort(r)
    r, p = r[order], p[order]
    a_fit, p0_fit = fit_elliptic(r, p)
    print(f"sphere section on a rigid plane: total force F = {F:.4f} (sphere_top reaction, "
          f"per full revolution), E* = {E_star:.3f}, {closed.sum()} nodes in contact")
    print(f"Hertz:   a = {a:.4f}   p0 = {p0:.4f}   approach {delta:.4f}")
    print(f"nodal:   p(axis) = {p[0]:.4f} ({C.relerr(p[0], p0)}), p_max = {p.max():.4f} "
          f"({C.relerr(p.max(), p0)}); last closed node at r = {r.max():.4f}")
    print(f"fitted:  a = {a_fit:.4f} ({C.relerr(a_fit, a)})   p0 = {p0_fit:.4f} "
          f"({C.relerr(p0_fit, p0)})   [p^2 = p0^2 (1 - r^2/a^2) on "
          f"{int((p > 0.2 * p.max()).sum())} nodes]")
    if not args.no_render:
        rs = np.linspace(0, 1.6 * a, 400)
        C.profile_plot(result, "hertz_axisymmetric_profile", r, p,
                       (rs, hertz_sphere_pressure(rs, F, R, E_star),
                        f"Hertz: a = {a:.4f}, p0 = {p0:.3f}"), a_fit,
                       "r (distance from the axis)", "Hertz: sphere section on a rigid plane")


if __name__ == "__main__":
    main()
