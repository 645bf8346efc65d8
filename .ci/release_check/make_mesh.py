"""Write blocks.msh for .ci/release_check/scene.toml: a 0.5 x 0.5 x 0.25 block on a
1 x 1 x 0.5 foundation, structured hexahedra, separate nodes.

    python3 make_mesh.py OUT.msh

The foundation has 4 faces per edge, the block 3, and the block stands at
(0.3, 0.3): no slave node lies on an edge of the master faces, during the
slide either, so which face a slave node pairs with is never decided by
round-off (it would be with matching grids, and the reactions of two
equally valid solutions would differ by far more than 1e-6).
"""
import sys

import gmsh


def face(occ, vol, z):
    for _, t in gmsh.model.getBoundary([(3, vol)], oriented=False):
        if abs(occ.getCenterOfMass(2, t)[2] - z) < 1e-9:
            return t
    raise RuntimeError(f"no face at z = {z}")


def main(out: str, n_found: int = 4, n_block: int = 3, corner: float = 0.3) -> None:
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("release_check")
        occ = gmsh.model.occ
        found = occ.addBox(0, 0, 0, 1, 1, 0.5)
        block = occ.addBox(corner, corner, 0.5, 0.5, 0.5, 0.25)
        occ.synchronize()
        m = gmsh.model.mesh
        for vol, n in ((found, n_found), (block, n_block)):
            for _, s in gmsh.model.getBoundary([(3, vol)], oriented=False):
                for _, c in gmsh.model.getBoundary([(2, s)], oriented=False):
                    m.setTransfiniteCurve(abs(c), n + 1)
        for _, tag in gmsh.model.getEntities(2):
            m.setTransfiniteSurface(tag)
            m.setRecombine(2, tag)
        for _, tag in gmsh.model.getEntities(3):
            m.setTransfiniteVolume(tag)

        def group(dim, tags, name):
            gmsh.model.setPhysicalName(dim, gmsh.model.addPhysicalGroup(dim, tags), name)

        group(3, [found], "foundation")
        group(3, [block], "block")
        group(2, [face(occ, found, 0.0)], "foundation_bottom")
        group(2, [face(occ, found, 0.5)], "foundation_top")
        group(2, [face(occ, block, 0.5)], "block_bottom")
        group(2, [face(occ, block, 0.75)], "block_top")
        m.generate(3)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.write(out)
    finally:
        gmsh.finalize()


if __name__ == "__main__":
    main(sys.argv[1], *(float(a) if "." in a else int(a) for a in sys.argv[2:]))
