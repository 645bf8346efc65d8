"""Write blocks.msh for .ci/release_check/scene.toml: a 0.5 x 0.5 x 0.25 block on a
1 x 1 x 0.5 foundation, structured hexahedra (n faces per edge), separate nodes.

    python3 make_mesh.py OUT.msh [n]
"""
import sys

import gmsh


def face(occ, vol, z):
    for _, t in gmsh.model.getBoundary([(3, vol)], oriented=False):
        if abs(occ.getCenterOfMass(2, t)[2] - z) < 1e-9:
            return t
    raise RuntimeError(f"no face at z = {z}")


def main(out: str, n: int = 4) -> None:
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("release_check")
        occ = gmsh.model.occ
        found = occ.addBox(0, 0, 0, 1, 1, 0.5)
        block = occ.addBox(0.25, 0.25, 0.5, 0.5, 0.5, 0.25)
        occ.synchronize()
        m = gmsh.model.mesh
        for _, tag in gmsh.model.getEntities(1):
            m.setTransfiniteCurve(tag, n + 1)
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
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 4)
