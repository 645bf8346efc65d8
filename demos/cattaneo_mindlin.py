"""Cattaneo–Mindlin partial slip: a cylinder pressed on a block, then loaded tangentially (2D).

Plane strain, both bodies E = 1000, nu = 0.3 (elastically similar, so the
normal and tangential problems uncouple), mu = 0.3.  A half disk (radius
R = 10, centre (0, R)) sits on a block (60 x 20); quadrilateral meshes are
refined around the contact.  Step 1 pushes the flat top of the half disk
down by 0.25 (u_x free, except at the centre of the top, held at u_x = 0).
Step 2 releases that point and applies a horizontal traction on the top whose
resultant is ``Q = 0.5 mu P`` (``P`` = the normal load of step 1), in 5
increments, keeping u_y.

Reference (Johnson §7.1, :mod:`dolfinx_friction.reference.analytic`): the contact
half-width ``a`` is Hertz's; the central stick zone has the half-width
``c = a sqrt(1 - Q/(mu P))`` and the tangential traction is
``q(x) = mu p0 [sqrt(1 - x^2/a^2) - (c/a) sqrt(1 - x^2/c^2)]``.  The script
measures ``c`` from the nodal stick/slip status and plots ``q(x)``.

    python demos/cattaneo_mindlin.py
    python -m dolfinx_friction run demos/cattaneo_mindlin.toml
"""
from __future__ import annotations

from pathlib import Path

import _common as C  # noqa: F401  (pyvista before dolfinx)
from demos import _meshing as G  # gmsh helpers, after _common (it puts the root on sys.path)
import numpy as np

from dolfinx_friction.reference.analytic import (cattaneo_mindlin_stick_half_width,
                                       cattaneo_mindlin_traction, effective_modulus,
                                       hertz_line, hertz_line_pressure)

SCENE = C.HERE / "cattaneo_mindlin.toml"
MESH = C.HERE / "cattaneo_mindlin.msh"
R, E, NU, MU = 10.0, 1000.0, 0.3, 0.3
BLOCK = (30.0, 20.0)  # half width, depth
Q_OVER_MU_P = 0.5
TOP_WIDTH = 2 * R


def build_mesh(path: Path, h_contact: float = 0.05, h_far: float = 2.5,
               master_ratio: float = 2.0, refine_radius: float = 2.5) -> None:
    """Half disk over a block, quadrilaterals refined near the origin.

    ``h_contact``: cylinder element size within ``refine_radius`` of the
    initial contact point (the block's is ``master_ratio`` times larger);
    ``h_far``: size far away.
    """
    with G.gmsh_model("cattaneo_mindlin") as gmsh:
        geo = gmsh.model.geo
        W, D = BLOCK
        c = geo.addPoint(0, R, 0)
        left, bottom, right = geo.addPoint(-R, R, 0), geo.addPoint(0, 0, 0), geo.addPoint(R, R, 0)
        arc1, arc2 = geo.addCircleArc(left, c, bottom), geo.addCircleArc(bottom, c, right)
        top1, top2 = geo.addLine(right, c), geo.addLine(c, left)  # c: a node on the top
        cyl = geo.addPlaneSurface([geo.addCurveLoop([arc1, arc2, top1, top2])])
        q = [geo.addPoint(-W, 0, 0), geo.addPoint(-W, -D, 0), geo.addPoint(W, -D, 0),
             geo.addPoint(W, 0, 0)]
        mid = geo.addPoint(0, 0, 0)  # refinement centre on the block top (not shared)
        b_left, b_bottom, b_right = (geo.addLine(q[0], q[1]), geo.addLine(q[1], q[2]),
                                     geo.addLine(q[2], q[3]))
        b_top1, b_top2 = geo.addLine(q[3], mid), geo.addLine(mid, q[0])
        block = geo.addPlaneSurface([geo.addCurveLoop([b_left, b_bottom, b_right, b_top1,
                                                       b_top2])])
        geo.synchronize()

        # element size h_contact (cylinder) and master_ratio * h_contact (block) up to
        # refine_radius from the initial contact point, growing to h_far 12 further out
        G.size_field([([bottom], h_contact, (2, cyl)),
                      ([mid], master_ratio * h_contact, (2, block))],
                     h_far, refine_radius, refine_radius + 12.0)
        G.quadrilaterals()

        G.physical_group(2, [cyl], "cylinder")
        G.physical_group(2, [block], "block")
        G.physical_group(1, [arc1, arc2], "cylinder_surface")
        G.physical_group(1, [top1, top2], "cylinder_top")
        G.physical_group(0, [c], "cylinder_top_centre")
        G.physical_group(1, [b_top1, b_top2], "block_top")
        G.physical_group(1, [b_bottom], "block_bottom")
        gmsh.model.mesh.generate(2)
        G.write_msh(path)


def profile_plot(result, x, qx, status, P, Q, c_num, shift) -> None:
    """Nodal tangential tractions against Cattaneo-Mindlin's q(x)."""
    E_star = effective_modulus(E, NU, E, NU)
    a_h, p0 = hertz_line(P, R, E_star)
    c = cattaneo_mindlin_stick_half_width(a_h, Q, MU, P)
    xs = np.linspace(-1.4 * a_h, 1.4 * a_h, 801)
    fig, ax = C.pyplot().subplots(figsize=(7.0, 4.2), dpi=120)
    ax.plot(xs, hertz_line_pressure(xs, P, R, E_star) * MU, "k--", lw=1,
            label="mu p (Hertz)")
    ax.plot(xs, cattaneo_mindlin_traction(xs, a_h, c, MU, p0), "k-",
            label=f"Cattaneo-Mindlin q(x), c = {c:.3f}")
    for st, color, name in ((1, "#1f77b4", "stick"), (2, "#d62728", "slip")):
        sel = status == st
        ax.plot(x[sel], qx[sel], "o", ms=3.5, color=color, label=f"nodal F_T,x / A_p ({name})")
    ax.axvspan(shift - c_num, shift + c_num, color="#1f77b4", alpha=0.08,
               label=f"measured stick zone, c = {c_num:.3f}")
    ax.set_xlabel("x")
    ax.set_ylabel("tangential traction")
    ax.set_xlim(-1.4 * a_h, 1.4 * a_h)
    ax.set_title(f"Cattaneo-Mindlin: Q/(mu P) = {Q / (MU * P):.3f}", fontsize=10)
    ax.legend(fontsize=7, loc="upper right")
    ax.grid(alpha=0.3)
    C.save_figure(fig, result, "cattaneo_mindlin_traction")


def main(argv=None) -> None:
    args, scene = C.command_line(__doc__, SCENE, argv)
    result = C.run_demo(args, scene, MESH, build_mesh)
    if not args.no_render:
        C.render(result, "cattaneo_mindlin", scalar="status", warp=5.0,
                 title="Cattaneo-Mindlin partial slip", contact_margin=0.25)
    st = C.contact_state(result)
    if C.MPI.COMM_WORLD.rank != 0:
        return
    first = [i for i in result.increments if i.step == 0][-1]
    last = result.increments[-1]
    P1 = abs(first.reactions["cylinder_top"][1])
    P = abs(last.reactions["cylinder_top"][1])
    Q = abs(last.reactions["block_bottom"][0])  # = the applied traction resultant
    Q_applied = Q_OVER_MU_P * MU * P1
    E_star = effective_modulus(E, NU, E, NU)
    a, p0 = hertz_line(P, R, E_star)
    c_ref = cattaneo_mindlin_stick_half_width(a, Q, MU, P)
    closed = st["status"] != 0
    x = st["X"][closed, 0]
    status = st["status"][closed]
    qx = st["tangential_force"][closed, 0] / st["area"][closed]
    order = np.argsort(x)
    x, status, qx = x[order], status[order], qx[order]
    # stick-zone edges: midway between the outermost stick node and its slipping neighbour
    sticking = np.flatnonzero(status == 1)
    lo, hi = sticking.min(), sticking.max()
    left = 0.5 * (x[lo] + x[lo - 1]) if lo > 0 else x[lo]
    right = 0.5 * (x[hi] + x[hi + 1]) if hi + 1 < len(x) else x[hi]
    c_num, shift = 0.5 * (right - left), 0.5 * (right + left)
    spacing = np.median(np.diff(x))
    a_num = 0.5 * (x.max() - x.min())
    print(f"normal load P = {P:.4f} (after step 1: {P1:.4f}), tangential load Q = {Q:.4f} "
          f"(applied {Q_applied:.4f}), Q/(mu P) = {Q / (MU * P):.4f}")
    print(f"contact half-width: Hertz a = {a:.4f}, closed nodes span +-{a_num:.4f}")
    print(f"stick half-width: c = {c_num:.4f} +- {0.5 * spacing:.4f} (centre {shift:+.4f}) "
          f"vs a sqrt(1 - Q/(mu P)) = "
          f"{c_ref:.4f} ({C.relerr(c_num, c_ref)}; node spacing {spacing:.4f} = "
          f"{100 * spacing / c_ref:.1f} % of c)")
    slip = status == 2
    ratio = (np.linalg.norm(st["tangential_force"][closed][order][slip], axis=1)
             / (MU * st["normal_force"][closed][order][slip]))
    print(f"slip nodes: |F_T|/(mu F_N) in [{ratio.min():.6f}, {ratio.max():.6f}] (Coulomb: 1)")
    inside = np.abs(x) < 0.7 * c_ref
    dev = qx[inside] - cattaneo_mindlin_traction(x[inside], a, c_ref, MU, p0)
    print(f"stick-zone traction (|x| < 0.7 c): mean deviation from q_CM {dev.mean():+.4f}, rms "
          f"{np.sqrt(np.mean(dev ** 2)):.4f} ({100 * np.sqrt(np.mean(dev ** 2)) / (MU * p0):.1f} "
          f"% of mu p0)")
    if not args.no_render:
        profile_plot(result, x, qx, status, P, Q, c_num, shift)


if __name__ == "__main__":
    main()
