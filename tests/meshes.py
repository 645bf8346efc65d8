"""Small Gmsh meshes shared by the tests: built on rank 0, written where all ranks see them."""
from __future__ import annotations

from pathlib import Path

import gmsh
from mpi4py import MPI


def _group(dim: int, tags: list[int], name: str) -> None:
    tag = gmsh.model.addPhysicalGroup(dim, tags)
    gmsh.model.setPhysicalName(dim, tag, name)


def _boundary(dim: int, entity: int, axis: int, value: float) -> list[int]:
    """Boundary entities of ``entity`` whose centre has coordinate ``axis`` equal to ``value``."""
    out = []
    for d, t in gmsh.model.getBoundary([(dim, entity)], oriented=False):
        if abs(gmsh.model.occ.getCenterOfMass(d, t)[axis] - value) < 1e-9:
            out.append(t)
    return out


def _write(build, path: Path, comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    if comm.rank == 0:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(path.stem)
        try:
            build()
            gmsh.write(str(path))
        finally:
            gmsh.finalize()
    comm.barrier()
    return path


def _box(x0, y0, z0, dx, dy, dz) -> int:
    box = gmsh.model.occ.addBox(x0, y0, z0, dx, dy, dz)
    gmsh.model.occ.synchronize()
    return box


def _mesh_boxes(boxes: list[tuple[int, tuple[int, int, int]]], tets: bool = False) -> None:
    """Structured hex (or tet) meshes of boxes, ``n`` = segments along x, y, z."""
    for box, n in boxes:
        for _, surf in gmsh.model.getBoundary([(3, box)], oriented=False):
            for _, curve in gmsh.model.getBoundary([(2, surf)], oriented=False):
                a, b = gmsh.model.getBoundary([(1, curve)], oriented=False)
                pa = gmsh.model.getValue(0, a[1], [])
                pb = gmsh.model.getValue(0, b[1], [])
                axis = max(range(3), key=lambda k: abs(pa[k] - pb[k]))
                gmsh.model.mesh.setTransfiniteCurve(curve, n[axis] + 1)
            gmsh.model.mesh.setTransfiniteSurface(surf)
            if not tets:
                gmsh.model.mesh.setRecombine(2, surf)
        gmsh.model.mesh.setTransfiniteVolume(box)
    gmsh.model.mesh.generate(3)


def block_3d(path: Path, n: tuple[int, int, int] = (4, 4, 2), tets: bool = False) -> Path:
    """Box [0,1]x[0,1]x[0,0.5]: body ``block``, facets ``bottom`` (z=0), ``top``, ``side_x0``, ``side_y0``."""
    def build():
        box = _box(0, 0, 0, 1, 1, 0.5)
        _mesh_boxes([(box, n)], tets)
        _group(3, [box], "block")
        _group(2, _boundary(3, box, 2, 0.0), "bottom")
        _group(2, _boundary(3, box, 2, 0.5), "top")
        _group(2, _boundary(3, box, 0, 0.0), "side_x0")
        _group(2, _boundary(3, box, 1, 0.0), "side_y0")
    return _write(build, path)


def two_boxes(path: Path, n_block: tuple[int, int, int] = (4, 4, 2),
              n_foundation: tuple[int, int, int] = (5, 5, 2)) -> Path:
    """Block [0.25,0.75]^2 x [0.5,0.75] on foundation [0,1]^2 x [0,0.5] (separate volumes).

    Groups: bodies ``block``, ``foundation``; facets ``block_bottom``, ``block_top``,
    ``foundation_top``, ``foundation_bottom``.
    """
    def build():
        f = _box(0, 0, 0, 1, 1, 0.5)
        b = _box(0.25, 0.25, 0.5, 0.5, 0.5, 0.25)
        _mesh_boxes([(f, n_foundation), (b, n_block)])
        _group(3, [f], "foundation")
        _group(3, [b], "block")
        _group(2, _boundary(3, f, 2, 0.0), "foundation_bottom")
        _group(2, _boundary(3, f, 2, 0.5), "foundation_top")
        _group(2, _boundary(3, b, 2, 0.5), "block_bottom")
        _group(2, _boundary(3, b, 2, 0.75), "block_top")
    return _write(build, path)


def rectangle_2d(path: Path, n: tuple[int, int] = (8, 2), quads: bool = True,
                 order: int = 1) -> Path:
    """Rectangle [0,1]x[0,0.25]: body ``block``, edges ``bottom``, ``top``, ``left``, ``right``."""
    def build():
        s = gmsh.model.occ.addRectangle(0, 0, 0, 1, 0.25)
        gmsh.model.occ.synchronize()
        for _, curve in gmsh.model.getBoundary([(2, s)], oriented=False):
            a, b = gmsh.model.getBoundary([(1, curve)], oriented=False)
            pa, pb = gmsh.model.getValue(0, a[1], []), gmsh.model.getValue(0, b[1], [])
            axis = 0 if abs(pa[0] - pb[0]) > abs(pa[1] - pb[1]) else 1
            gmsh.model.mesh.setTransfiniteCurve(curve, n[axis] + 1)
        gmsh.model.mesh.setTransfiniteSurface(s)
        if quads:
            gmsh.model.mesh.setRecombine(2, s)
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(order)
        _group(2, [s], "block")
        _group(1, _boundary(2, s, 1, 0.0), "bottom")
        _group(1, _boundary(2, s, 1, 0.25), "top")
        _group(1, _boundary(2, s, 0, 0.0), "left")
        _group(1, _boundary(2, s, 0, 1.0), "right")
    return _write(build, path)
