"""Elastic block pressed onto an elastic foundation, then slid (3D, hexahedra, mu = 0.3).

The block (20 x 20 x 10) sits on a foundation (60 x 30 x 10); the slave
surface (block bottom, 7 x 7 faces) and the master surface (foundation top,
12 x 6 faces) have mismatched meshes.  Step 1 presses the block top down by
0.02 (a rigid platen: all three components prescribed), step 2 moves it by
10 along x in 10 increments with the same vertical displacement.

Reference: once every slave node slips, the tangential force is mu times
the normal force node by node, so the platen reaction satisfies
``|R_x| / |R_z| = mu`` (up to the small y-component of the slip).

    python demos/sliding_block.py            # builds the mesh if needed, runs, renders
    python -m dolfinx_friction run demos/sliding_block.toml
"""
from __future__ import annotations

from pathlib import Path

import _common as C  # noqa: F401  (pyvista before dolfinx)
from demos import _meshing as G  # gmsh helpers, after _common (it puts the root on sys.path)

SCENE = C.HERE / "sliding_block.toml"
MESH = C.HERE / "sliding_block.msh"
MU = 0.3


def build_mesh(path: Path, n_block: int = 7, n_found: tuple[int, int] = (12, 6),
               layers: tuple[int, int] = (3, 3)) -> None:
    """Hexahedral block and foundation (separate nodes, no shared surface).

    ``n_block``: faces along each side of the block bottom; ``n_found``: faces of
    the foundation top along x and y; ``layers``: elements through the
    thickness of the block and of the foundation.
    """
    with G.gmsh_model("sliding_block") as gmsh:
        occ = gmsh.model.occ
        found = occ.addBox(0, 0, 0, 60, 30, 10)
        block = occ.addBox(10, 5, 10, 20, 20, 10)
        occ.synchronize()
        m = gmsh.model.mesh

        for vol, (nx, ny, nz) in ((found, (*n_found, layers[1])),
                                  (block, (n_block, n_block, layers[0]))):
            curves = {c for _, s in gmsh.model.getBoundary([(3, vol)], oriented=False)
                      for _, c in gmsh.model.getBoundary([(2, s)], oriented=False)}
            for c in curves:
                x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(1, c)
                dx, dy, dz = x1 - x0, y1 - y0, z1 - z0
                n = nx if dx > max(dy, dz) else ny if dy > dz else nz
                m.setTransfiniteCurve(c, n + 1)
            for _, s in gmsh.model.getBoundary([(3, vol)], oriented=False):
                m.setTransfiniteSurface(s)
                m.setRecombine(2, s)
            m.setTransfiniteVolume(vol)

        def face(vol, axis, value):
            for _, s in gmsh.model.getBoundary([(3, vol)], oriented=False):
                com = occ.getCenterOfMass(2, s)
                if abs(com[axis] - value) < 1e-9:
                    return s
            raise RuntimeError("face not found")

        G.physical_group(3, [block], "block")
        G.physical_group(3, [found], "foundation")
        G.physical_group(2, [face(block, 2, 10.0)], "block_bottom")
        G.physical_group(2, [face(block, 2, 20.0)], "block_top")
        G.physical_group(2, [face(found, 2, 10.0)], "foundation_top")
        G.physical_group(2, [face(found, 2, 0.0)], "foundation_bottom")
        m.generate(3)
        G.write_msh(path)


def main(argv=None) -> None:
    args, scene = C.command_line(__doc__, SCENE, argv)
    result = C.run_demo(args, scene, MESH, build_mesh)
    if not args.no_render:
        C.render_status_and_pressure(result, "sliding_block", warp=50.0, amplify="deformation",
                                     title="block slid on a foundation, mu = 0.3")
    C.root_print("increment  slipping/active   -R_x/R_z (platen)")
    for inc in result.increments:
        R = inc.reactions["block_top"]
        C.root_print(f"{C.increment_line(inc)}        {abs(R[0]) / abs(R[2]):.5f}")
    R = result.increments[-1].reactions["block_top"]
    ratio = abs(R[0]) / abs(R[2])
    C.root_print(f"final friction ratio |R_x|/|R_z| = {ratio:.5f}  vs mu = {MU} "
                 f"({C.relerr(ratio, MU)}); normal force {abs(R[2]):.1f}")


if __name__ == "__main__":
    main()
