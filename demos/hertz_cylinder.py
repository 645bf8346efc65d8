"""Hertz line contact: an elastic cylinder pressed onto an elastic block (2D plane strain).

Quarter model with symmetry about ``x = 0``: a quarter disk (radius R = 10,
centre (0, R)) on a half block (30 x 20).  Both bodies have E = 1000,
nu = 0.3; the meshes (quadrilaterals) are refined around the first point of
contact, the cylinder (slave) about twice as finely as the block (master).
The flat top of the quarter disk is pushed down by 0.25 in 4 increments,
frictionless.

Reference (Johnson §4.3, :func:`dolfinx_friction.reference.analytic.hertz_line`): with
the load per unit length of the whole cylinder ``P = 2 |R_top_y|``,
``a = sqrt(4 P R / (pi E*))`` and ``p0 = 2 P / (pi a)``, ``1/E* = 2 (1-nu^2)/E``.
The script fits the elliptic profile ``p^2 = p0^2 (1 - x^2/a^2)`` to the nodal
pressures and also reports the largest nodal pressure; a picture of the
profile against Hertz is written next to the results.

    python demos/hertz_cylinder.py
    python -m dolfinx_friction run demos/hertz_cylinder.toml [--set body.0.degree=2]
"""
from __future__ import annotations

from pathlib import Path

import _common as C  # noqa: F401  (pyvista before dolfinx)
from demos import _meshing as G  # gmsh helpers, after _common (it puts the root on sys.path)
import numpy as np

from dolfinx_friction.reference.analytic import (effective_modulus, fit_elliptic, hertz_line,
                                       hertz_line_pressure)

SCENE = C.HERE / "hertz_cylinder.toml"
MESH = C.HERE / "hertz_cylinder.msh"
R, E, NU = 10.0, 1000.0, 0.3
BLOCK = (30.0, 20.0)  # half width, depth


def build_mesh(path: Path, h_contact: float = 0.05, h_far: float = 2.5,
               master_ratio: float = 2.0, refine_radius: float = 2.5, order: int = 1) -> None:
    """Quarter disk over a half block, quadrilaterals refined near the origin.

    ``h_contact``: cylinder element size within ``refine_radius`` of the first
    contact point (the block's is ``master_ratio`` times larger); ``h_far``:
    size far away; ``order``: geometric order (2: mid-side nodes on the arc).
    """
    with G.gmsh_model("hertz_cylinder") as gmsh:
        geo = gmsh.model.geo
        W, D = BLOCK
        # cylinder: quarter disk x >= 0, centre (0, R)
        c = geo.addPoint(0, R, 0)
        p0, p1 = geo.addPoint(0, 0, 0), geo.addPoint(R, R, 0)
        arc = geo.addCircleArc(p0, c, p1)
        top = geo.addLine(p1, c)
        sym = geo.addLine(c, p0)
        cyl = geo.addPlaneSurface([geo.addCurveLoop([arc, top, sym])])
        # block: [0, W] x [-D, 0] (its own points: no node is shared with the cylinder)
        q = [geo.addPoint(0, 0, 0), geo.addPoint(0, -D, 0), geo.addPoint(W, -D, 0),
             geo.addPoint(W, 0, 0)]
        b_sym, b_bottom, b_right, b_top = (geo.addLine(q[0], q[1]), geo.addLine(q[1], q[2]),
                                           geo.addLine(q[2], q[3]), geo.addLine(q[3], q[0]))
        block = geo.addPlaneSurface([geo.addCurveLoop([b_sym, b_bottom, b_right, b_top])])
        geo.synchronize()

        # element size h_contact (cylinder) and master_ratio * h_contact (block) up to
        # refine_radius from the first contact point, growing to h_far 12 further out
        G.size_field([([p0], h_contact, (2, cyl)), ([q[0]], master_ratio * h_contact, (2, block))],
                     h_far, refine_radius, refine_radius + 12.0)
        G.quadrilaterals()

        G.physical_group(2, [cyl], "cylinder")
        G.physical_group(2, [block], "block")
        G.physical_group(1, [arc], "cylinder_surface")
        G.physical_group(1, [top], "cylinder_top")
        G.physical_group(1, [sym], "cylinder_symmetry")
        G.physical_group(1, [b_top], "block_top")
        G.physical_group(1, [b_bottom], "block_bottom")
        G.physical_group(1, [b_sym], "block_symmetry")
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(order)
        G.write_msh(path)


def main(argv=None) -> None:
    args, scene = C.command_line(__doc__, SCENE, argv)
    result = C.run_demo(args, scene, MESH, build_mesh)
    if not args.no_render:
        C.render(result, "hertz_cylinder", warp=1.0, title="Hertz line contact (quarter model)")
    st = C.contact_state(result)
    if C.MPI.COMM_WORLD.rank != 0:
        return
    P = 2.0 * abs(result.increments[-1].reactions["cylinder_top"][1])
    E_star = effective_modulus(E, NU, E, NU)
    a, p0 = hertz_line(P, R, E_star)
    closed = st["status"] != 0
    x, p = st["X"][closed, 0], st["pressure"][closed]
    order = np.argsort(x)
    x, p = x[order], p[order]
    a_fit, p0_fit = fit_elliptic(x, p)
    x_all = st["X_all"][:, 0]
    x_first_open = x_all[x_all > x.max()].min() if np.any(x_all > x.max()) else np.nan
    print(f"load per unit length P = {P:.4f} (2 x cylinder_top reaction), E* = {E_star:.3f}, "
          f"2 sum F_N / P = {2 * st['F_N'][closed].sum() / P:.8f}")
    print(f"Hertz:   a = {a:.4f}   p0 = {p0:.4f}")
    print(f"nodal:   p_max = {p.max():.4f} ({C.relerr(p.max(), p0)})   last closed node at "
          f"x = {x.max():.4f}, first open at {x_first_open:.4f} (a = {a:.4f})")
    print(f"fitted:  a = {a_fit:.4f} ({C.relerr(a_fit, a)})   p0 = {p0_fit:.4f} "
          f"({C.relerr(p0_fit, p0)})   [p^2 = p0^2 (1 - x^2/a^2) on "
          f"{int((p > 0.2 * p.max()).sum())} nodes]")
    inside = x < 0.9 * a
    err = np.abs(p[inside] - hertz_line_pressure(x[inside], P, R, E_star)).max() / p0
    print(f"max |p - p_Hertz| / p0 over |x| < 0.9 a: {100 * err:.2f} %")
    if not args.no_render:  # nodal pressures against Hertz
        xs = np.linspace(0, 1.6 * a, 400)
        C.profile_plot(result, "hertz_cylinder_profile", x, p,
                       (xs, hertz_line_pressure(xs, P, R, E_star),
                        f"Hertz: a = {a:.4f}, p0 = {p0:.3f}"), a_fit,
                       "x (distance from the symmetry plane)",
                       "Hertz line contact: cylinder on a block")


if __name__ == "__main__":
    main()
