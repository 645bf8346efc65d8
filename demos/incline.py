"""Block on a rigid inclined plane, pressed by a vertical load, then pushed up the slope (2D).

CGS-4-like benchmark in plane strain: a block (length 10 along x, height 5 at
the low end) whose bottom lies on a rigid plane rising with slope
``tan(alpha) = 0.1``; ``mu = 0.3``.  Step 1 applies a vertical traction
``q = 10`` on the horizontal top face (total ``V = 100`` per unit thickness)
while the top is held horizontally (``u_x = 0``, ``u_y`` free).  Step 2 pushes
the top horizontally by 0.5 (10 increments), ``u_y`` still free and the load
still on, until every contact node slips up the slope.

Reference (statics of a block on a rough incline, see
:func:`dolfinx_friction.reference.analytic.incline_push_ratio`): in full slip the
horizontal push over the vertical load is ``H/V = (tan a + mu)/(1 - mu tan a)``.

    python demos/incline.py
    python -m dolfinx_friction run demos/incline.toml
"""
from __future__ import annotations

import math
from pathlib import Path

import _common as C  # noqa: F401  (pyvista before dolfinx)
from demos import _meshing as G  # gmsh helpers, after _common (it puts the root on sys.path)

from dolfinx_friction.reference.analytic import incline_push_ratio, incline_hold_ratio

SCENE = C.HERE / "incline.toml"
MESH = C.HERE / "incline.msh"
TAN_ALPHA, MU = 0.1, 0.3
LENGTH, HEIGHT, Q = 10.0, 5.0, 10.0


def build_mesh(path: Path, nx: int = 20, ny: int = 10) -> None:
    """Quadrilateral block whose bottom follows the slope ``y = x tan(alpha)``.

    ``nx`` elements along the slope, ``ny`` across the height.
    """
    with G.gmsh_model("incline") as gmsh:
        geo = gmsh.model.geo
        p = [geo.addPoint(0, 0, 0), geo.addPoint(LENGTH, LENGTH * TAN_ALPHA, 0),
             geo.addPoint(LENGTH, HEIGHT, 0), geo.addPoint(0, HEIGHT, 0)]
        lines = [geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
        surface = geo.addPlaneSurface([geo.addCurveLoop(lines)])
        geo.synchronize()
        m = gmsh.model.mesh
        for i, line in enumerate(lines):
            m.setTransfiniteCurve(line, (nx if i % 2 == 0 else ny) + 1)
        m.setTransfiniteSurface(surface)
        m.setRecombine(2, surface)

        G.physical_group(2, [surface], "block")
        G.physical_group(1, [lines[0]], "block_bottom")
        G.physical_group(1, [lines[2]], "block_top")
        m.generate(2)
        G.write_msh(path)


def main(argv=None) -> None:
    args, scene = C.command_line(__doc__, SCENE, argv)
    result = C.run_demo(args, scene, MESH, build_mesh)
    if not args.no_render:
        C.render_status_and_pressure(
            result, "incline", warp=5.0, panels=("overview",),
            title="block pushed up a rigid slope (tan a = 0.1, mu = 0.3)")
    V = Q * LENGTH
    ref = incline_push_ratio(TAN_ALPHA, MU)
    C.root_print(f"reference H/V = (tan a + mu)/(1 - mu tan a) = {ref:.6f}  "
                 f"(sliding down would need H/V = {incline_hold_ratio(TAN_ALPHA, MU):+.4f})")
    C.root_print("step   inc  slipping/active   H/V")
    for inc in result.increments:
        H = inc.reactions["block_top"][0]
        C.root_print(f"{C.increment_line(inc)}          {H / V:.6f}")
    H = result.increments[-1].reactions["block_top"][0]
    C.root_print(f"final H/V = {H / V:.6f} vs {ref:.6f} ({C.relerr(H / V, ref)}); "
                 f"alpha = {math.degrees(math.atan(TAN_ALPHA)):.3f} deg")


if __name__ == "__main__":
    main()
