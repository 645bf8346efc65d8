"""Gmsh plumbing of the demos' ``build_mesh`` functions: session, groups, size field, file.

Needs gmsh only (no pyvista, no dolfinx), apart from ``_common``: the benchmarks
import a demo for its ``build_mesh`` with a stub in place of ``_common``
(``benchmarks/_bench.py``, ``benchmarks/stability/_scenes.py``), because
pyvista must not be loaded after dolfinx.  The demos import it as
``from demos import _meshing as G``: the repository root is on ``sys.path``
in every case (``_common`` and the benchmarks put it there).
"""
from __future__ import annotations

import contextlib
from pathlib import Path
from typing import Iterator, Sequence

#: the list option of a gmsh ``Restrict`` field for the entities of each dimension
_RESTRICT_LISTS = {3: "VolumesList", 2: "SurfacesList", 1: "CurvesList"}


@contextlib.contextmanager
def gmsh_model(name: str) -> Iterator:
    """The gmsh module, initialised and silent, with a new model ``name``; finalized on exit."""
    import gmsh
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(name)
        yield gmsh
    finally:
        gmsh.finalize()


def quadrilaterals() -> None:
    """Mesh surfaces with Frontal-Delaunay for quads (algorithm 6) and recombine every
    triangle pair into quadrilaterals (Blossom)."""
    import gmsh
    for key, value in (("Mesh.Algorithm", 6), ("Mesh.RecombineAll", 1),
                       ("Mesh.RecombinationAlgorithm", 1)):
        gmsh.option.setNumber(key, value)


def physical_group(dim: int, tags: Sequence[int], name: str) -> int:
    """Add the physical group ``name`` of the entities ``tags`` of dimension ``dim``."""
    import gmsh
    tag = gmsh.model.addPhysicalGroup(dim, list(tags))
    gmsh.model.setPhysicalName(dim, tag, name)
    return tag


def size_field(regions: Sequence[tuple[Sequence[int], float, tuple[int, int]]], h_far: float,
               dist_min: float, dist_max: float) -> None:
    """Background mesh size: ``h`` near the points of each ``(points, h, (dim, tag))``."""
    # per region: h up to dist_min from the points, growing linearly to h_far at dist_max,
    # applied only on the entity (dim, tag) and its boundary; the smallest size wins
    import gmsh
    f = gmsh.model.mesh.field
    fields = []
    for points, h, (dim, tag) in regions:
        dist = f.add("Distance")
        f.setNumbers(dist, "PointsList", list(points))
        thr = f.add("Threshold")
        f.setNumber(thr, "InField", dist)
        f.setNumber(thr, "SizeMin", h)
        f.setNumber(thr, "SizeMax", h_far)
        f.setNumber(thr, "DistMin", dist_min)
        f.setNumber(thr, "DistMax", dist_max)
        restrict = f.add("Restrict")
        f.setNumber(restrict, "InField", thr)
        tags = [tag]
        for d in range(dim, 0, -1):  # the entity, its boundary, the boundary's boundary, ...
            f.setNumbers(restrict, _RESTRICT_LISTS[d], tags)
            tags = sorted({t for _, t in gmsh.model.getBoundary(
                [(d, t) for t in tags], combined=False, oriented=False)})
        fields.append(restrict)
    fmin = f.add("Min")
    f.setNumbers(fmin, "FieldsList", fields)
    f.setAsBackgroundMesh(fmin)
    for key in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints",
                "Mesh.MeshSizeFromCurvature"):  # the field alone sets the size
        gmsh.option.setNumber(key, 0)


def write_msh(path: Path, binary: bool = False) -> None:
    """Check that the cells are of one type (as dolfinx 0.5 requires), write MSH 4.1."""
    import gmsh
    dim = gmsh.model.getDimension()
    types = gmsh.model.mesh.getElementTypes(dim)
    if len(types) != 1:
        raise RuntimeError(f"mixed {dim}D element types {types}: mesh differently")
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    if binary:
        gmsh.option.setNumber("Mesh.Binary", 1)
    gmsh.write(str(path))
