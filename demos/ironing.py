"""Ironing: a stiff indenter pressed into a soft elastic block and dragged along it (2D, mu = 0.3).

Plane strain.  A block (20 x 5, E = 10, nu = 0.3, bottom fixed) is indented
by a stiff elastic half disk (radius 2, E = 10^4, i.e. 1000 times stiffer)
whose flat top is moved down by 0.5 in 4 increments, then 4 (one indenter
diameter) along x in 64 increments at that depth.  The block top is the slave surface, the indenter's
arc the master.  (A rigid ``[[rigid]]`` circle in place of the elastic
indenter does not converge with large drag increments: see demos/README.md.)

No closed-form solution exists for the finite block; the script reports the
drag ratio ``|R_x| / |R_y|`` of the indenter (it tends to mu plus a small
geometric part from the tilted normals at the leading and trailing edges of
the contact), the number of sliding nodes, and the Newton iterations.

    python demos/ironing.py
    python -m dolfinx_friction run demos/ironing.toml
"""
from __future__ import annotations

from pathlib import Path

import _common as C  # noqa: F401  (pyvista before dolfinx)
from demos import _meshing as G  # gmsh helpers, after _common (it puts the root on sys.path)

SCENE = C.HERE / "ironing.toml"
MESH = C.HERE / "ironing.msh"
MU = 0.3
LENGTH, HEIGHT = 20.0, 5.0
RADIUS, X0 = 2.0, 3.0


def build_mesh(path: Path, nx: int = 120, ny: int = 24, bias: float = 0.9,
               n_arc: int = 40) -> None:
    """Structured quadrilateral block graded towards the top, and a half-disk indenter.

    Block: ``nx`` x ``ny`` elements, ``bias`` < 1 makes the rows thinner towards
    the top.  Indenter (radius 2, centre (3, 7), flat top at y = 7): ``n_arc``
    elements along its arc (quadrilaterals).
    """
    with G.gmsh_model("ironing") as gmsh:
        geo = gmsh.model.geo
        p = [geo.addPoint(0, 0, 0), geo.addPoint(LENGTH, 0, 0), geo.addPoint(LENGTH, HEIGHT, 0),
             geo.addPoint(0, HEIGHT, 0)]
        bottom, right, top, left = (geo.addLine(p[0], p[1]), geo.addLine(p[1], p[2]),
                                    geo.addLine(p[2], p[3]), geo.addLine(p[3], p[0]))
        surface = geo.addPlaneSurface([geo.addCurveLoop([bottom, right, top, left])])
        cx, cy = X0, HEIGHT + RADIUS
        c = geo.addPoint(cx, cy, 0)
        a, b, d = (geo.addPoint(cx - RADIUS, cy, 0), geo.addPoint(cx, cy - RADIUS, 0),
                   geo.addPoint(cx + RADIUS, cy, 0))
        arc1, arc2 = geo.addCircleArc(a, c, b), geo.addCircleArc(b, c, d)
        die_top = geo.addLine(d, a)
        die = geo.addPlaneSurface([geo.addCurveLoop([arc1, arc2, die_top])])
        geo.synchronize()
        m = gmsh.model.mesh
        # the subdivision below halves every element: mesh with half the counts
        m.setTransfiniteCurve(bottom, nx // 2 + 1)
        m.setTransfiniteCurve(top, nx // 2 + 1)
        m.setTransfiniteCurve(right, ny // 2 + 1, "Progression", bias)   # upwards: thinner rows
        m.setTransfiniteCurve(left, ny // 2 + 1, "Progression", 1.0 / bias)  # downwards
        m.setTransfiniteSurface(surface)
        m.setRecombine(2, surface)
        for arc in (arc1, arc2):
            m.setTransfiniteCurve(arc, n_arc // 4 + 1)  # halved again by the subdivision
        m.setRecombine(2, die)
        # all-quadrilateral: recombine, then split every cell into quadrilaterals
        gmsh.option.setNumber("Mesh.MeshSizeMax", RADIUS / 4)
        gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 1)
        gmsh.option.setNumber("Mesh.SubdivisionAlgorithm", 1)

        G.physical_group(2, [surface], "block")
        G.physical_group(1, [top], "block_top")
        G.physical_group(1, [bottom], "block_bottom")
        G.physical_group(2, [die], "die")
        G.physical_group(1, [arc1, arc2], "die_surface")
        G.physical_group(1, [die_top], "die_top")
        m.generate(2)
        G.write_msh(path)


def main(argv=None) -> None:
    args, scene = C.command_line(__doc__, SCENE, argv)
    result = C.run_demo(args, scene, MESH, build_mesh)
    if not args.no_render:
        C.render_status_and_pressure(
            result, "ironing", warp=1.0, contact_margin=1.0,
            title="ironing: stiff indenter dragged over a soft block, mu = 0.3")
    C.root_print("step     inc   active slipping   R_y        |R_x|/|R_y|   (die_top reaction)")
    ratios = []
    for inc in result.increments:
        F = inc.reactions["die_top"]
        ratio = abs(F[0]) / abs(F[1]) if F[1] else float("nan")
        if inc.step_name == "drag":
            ratios.append(ratio)
        if inc.step_name == "press" or inc.increment % 8 == 0:
            C.root_print(f"{inc.step_name:>6} {inc.increment:4d}   {inc.active:5d} "
                         f"{inc.slipping:6d}   {F[1]:10.4f}   {ratio:.4f}")
    steady = ratios[len(ratios) // 4:]
    C.root_print(f"drag ratio |R_x|/|R_y| over the last 3/4 of the drag: {min(steady):.4f} .. "
                 f"{max(steady):.4f} (mu = {MU}); final {ratios[-1]:.4f}")


if __name__ == "__main__":
    main()
