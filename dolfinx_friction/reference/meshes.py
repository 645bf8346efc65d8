"""Small Gmsh meshes of the verification cases and the benchmarks: built on rank 0, written
where all ranks see them (``comm``'s ranks wait for rank 0).

Bodies are physical groups of cells, facet groups name the faces the scenes use; lengths
are dimensionless.  Meridian sections of axisymmetric bodies (r = x >= 0, z = y):
:func:`thick_cylinders`, :func:`sphere_section`, :func:`ring_section`.  The CalculiX
comparisons' meshes: :func:`blocks_on_foundation`, :func:`ironing` (with their scenes in
:mod:`dolfinx_friction.reference.cases`); Hertz contact on a rigid plane:
:func:`quarter_disk`, :func:`quarter_sphere` (also on an elastic block); the stability
tests' and maps' sliding block: :func:`block_on_foundation`.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

import gmsh
from mpi4py import MPI


def group(dim: int, tags: list[int], name: str) -> None:
    """Name the entities ``tags`` of dimension ``dim`` a physical group ``name``."""
    tag = gmsh.model.addPhysicalGroup(dim, tags)
    gmsh.model.setPhysicalName(dim, tag, name)


def boundary(dim: int, entity: int, axis: int, value: float) -> list[int]:
    """Boundary entities of ``entity`` whose centre has coordinate ``axis`` equal to ``value``."""
    out = []
    for d, t in gmsh.model.getBoundary([(dim, entity)], oriented=False):
        if abs(gmsh.model.occ.getCenterOfMass(d, t)[axis] - value) < 1e-9:
            out.append(t)
    return out


def write_model(build, path: Path, comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """Run ``build()`` on a fresh Gmsh model on rank 0 and write the mesh to ``path``;
    every rank of ``comm`` returns ``path`` once it is written."""
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


def box(x0: float, y0: float, z0: float, dx: float, dy: float, dz: float) -> int:
    """An OpenCASCADE box (its volume tag), synchronised."""
    tag = gmsh.model.occ.addBox(x0, y0, z0, dx, dy, dz)
    gmsh.model.occ.synchronize()
    return tag


def mesh_boxes(boxes: list[tuple[int, tuple[int, int, int]]], tets: bool = False) -> None:
    """Structured hex (or tet) meshes of boxes, ``n`` = segments along x, y, z."""
    for volume, n in boxes:
        for _, surf in gmsh.model.getBoundary([(3, volume)], oriented=False):
            for _, curve in gmsh.model.getBoundary([(2, surf)], oriented=False):
                a, b = gmsh.model.getBoundary([(1, curve)], oriented=False)
                pa = gmsh.model.getValue(0, a[1], [])
                pb = gmsh.model.getValue(0, b[1], [])
                axis = max(range(3), key=lambda k: abs(pa[k] - pb[k]))
                gmsh.model.mesh.setTransfiniteCurve(curve, n[axis] + 1)
            gmsh.model.mesh.setTransfiniteSurface(surf)
            if not tets:
                gmsh.model.mesh.setRecombine(2, surf)
        gmsh.model.mesh.setTransfiniteVolume(volume)
    gmsh.model.mesh.generate(3)


def block_3d(path: Path, n: tuple[int, int, int] = (4, 4, 2), tets: bool = False) -> Path:
    """Box [0,1]x[0,1]x[0,0.5]: body ``block``, facets ``bottom`` (z=0), ``top``,
    ``side_x0``, ``side_y0``."""
    def build():
        b = box(0, 0, 0, 1, 1, 0.5)
        mesh_boxes([(b, n)], tets)
        group(3, [b], "block")
        group(2, boundary(3, b, 2, 0.0), "bottom")
        group(2, boundary(3, b, 2, 0.5), "top")
        group(2, boundary(3, b, 0, 0.0), "side_x0")
        group(2, boundary(3, b, 1, 0.0), "side_y0")
    return write_model(build, path)


def two_boxes(path: Path, n_block: tuple[int, int, int] = (4, 4, 2),
              n_foundation: tuple[int, int, int] = (5, 5, 2), tets: bool = False) -> Path:
    """Block [0.25,0.75]^2 x [0.5,0.75] on foundation [0,1]^2 x [0,0.5] (separate volumes;
    structured hexahedra, or with ``tets`` tetrahedra).

    Groups: bodies ``block``, ``foundation``; facets ``block_bottom``, ``block_top``,
    ``foundation_top``, ``foundation_bottom``.
    """
    def build():
        f = box(0, 0, 0, 1, 1, 0.5)
        b = box(0.25, 0.25, 0.5, 0.5, 0.5, 0.25)
        mesh_boxes([(f, n_foundation), (b, n_block)], tets)
        group(3, [f], "foundation")
        group(3, [b], "block")
        group(2, boundary(3, f, 2, 0.0), "foundation_bottom")
        group(2, boundary(3, f, 2, 0.5), "foundation_top")
        group(2, boundary(3, b, 2, 0.5), "block_bottom")
        group(2, boundary(3, b, 2, 0.75), "block_top")
    return write_model(build, path)


def rectangle_2d(path: Path, n: tuple[int, int] = (8, 2), quads: bool = True,
                 order: int = 1) -> Path:
    """Rectangle [0,1]x[0,0.25]: body ``block``, edges ``bottom``, ``top``, ``left``, ``right``."""
    def build():
        s = gmsh.model.occ.addRectangle(0, 0, 0, 1, 0.25)
        gmsh.model.occ.synchronize()
        _transfinite_rectangle(s, n, quads)
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(order)
        group(2, [s], "block")
        group(1, boundary(2, s, 1, 0.0), "bottom")
        group(1, boundary(2, s, 1, 0.25), "top")
        group(1, boundary(2, s, 0, 0.0), "left")
        group(1, boundary(2, s, 0, 1.0), "right")
    return write_model(build, path)


def structured_rectangle(x0: float, y0: float, w: float, h: float, nx: int, ny: int
                         ) -> tuple[int, dict[str, int]]:
    """The rectangle [x0, x0 + w] x [y0, y0 + h] in gmsh's geo kernel, meshed by nx x ny
    quadrilaterals (synchronized; the constraints survive later synchronizations): its
    surface tag and its edges' tags by side, ``bottom``, ``right``, ``top``, ``left``."""
    geo = gmsh.model.geo
    p = [geo.addPoint(x0, y0, 0), geo.addPoint(x0 + w, y0, 0), geo.addPoint(x0 + w, y0 + h, 0),
         geo.addPoint(x0, y0 + h, 0)]
    lines = [geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
    s = geo.addPlaneSurface([geo.addCurveLoop(lines)])
    for i, line in enumerate(lines):
        geo.mesh.setTransfiniteCurve(line, (nx if i % 2 == 0 else ny) + 1)
    geo.mesh.setTransfiniteSurface(s)
    geo.mesh.setRecombine(2, s)
    geo.synchronize()
    return s, dict(zip(("bottom", "right", "top", "left"), lines))


def tip_in_groove(path: Path, h: float = 0.0625, slope_master: float = 0.1,
                  slope_slave: float = 0.2, comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """A block whose bottom is a convex V (tip at (0.5, 0)) over a foundation [0, 1] x
    [-0.5, 0] whose top is a concave V-groove (bottom at (0.5, 0)), triangles of size ``h``:
    the tip node sits on the edge between the two groove faces, each of which pushes it
    towards the other.  Bodies ``block``, ``foundation``; edges ``tip``, ``block_top``,
    ``groove``, ``foundation_bottom``."""
    def build():
        geo = gmsh.model.geo
        f = [geo.addPoint(0, -0.5, 0, h), geo.addPoint(1, -0.5, 0, h),
             geo.addPoint(1, 0.5 * slope_master, 0, h), geo.addPoint(0.5, 0, 0, h),
             geo.addPoint(0, 0.5 * slope_master, 0, h)]
        fl = [geo.addLine(f[i], f[(i + 1) % 5]) for i in range(5)]
        fs = geo.addPlaneSurface([geo.addCurveLoop(fl)])
        b = [geo.addPoint(0.25, 0.25 * slope_slave, 0, h), geo.addPoint(0.5, 0, 0, h),
             geo.addPoint(0.75, 0.25 * slope_slave, 0, h), geo.addPoint(0.75, 0.3, 0, h),
             geo.addPoint(0.25, 0.3, 0, h)]
        bl = [geo.addLine(b[i], b[(i + 1) % 5]) for i in range(5)]
        bs = geo.addPlaneSurface([geo.addCurveLoop(bl)])
        for line in bl[:2]:
            geo.mesh.setTransfiniteCurve(line, round(0.25 / h) + 1)
        for line in fl[2:4]:
            geo.mesh.setTransfiniteCurve(line, round(0.5 / h) + 1)
        geo.synchronize()
        group(2, [fs], "foundation")
        group(2, [bs], "block")
        group(1, fl[2:4], "groove")
        group(1, [fl[0]], "foundation_bottom")
        group(1, bl[:2], "tip")
        group(1, [bl[3]], "block_top")
        gmsh.model.mesh.generate(2)
    return write_model(build, path, comm)


def _transfinite_rectangle(s: int, n: tuple[int, int], quads: bool) -> None:
    """A structured mesh of the rectangle surface ``s``: ``n`` = segments along x, y."""
    for _, curve in gmsh.model.getBoundary([(2, s)], oriented=False):
        a, b = gmsh.model.getBoundary([(1, curve)], oriented=False)
        pa, pb = gmsh.model.getValue(0, a[1], []), gmsh.model.getValue(0, b[1], [])
        axis = 0 if abs(pa[0] - pb[0]) > abs(pa[1] - pb[1]) else 1
        gmsh.model.mesh.setTransfiniteCurve(curve, n[axis] + 1)
    gmsh.model.mesh.setTransfiniteSurface(s)
    if quads:
        gmsh.model.mesh.setRecombine(2, s)


def thick_cylinders(path: Path, r_i: float = 1.0, r_c: float = 2.0, r_o: float = 3.0,
                    delta: float = 0.01, height: float = 0.5, n: tuple[int, int] = (16, 4),
                    quads: bool = True, order: int = 1,
                    comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """Meridian sections (r = x, z = y) of two thick cylinders for a shrink fit: the inner
    one ``[r_i, r_c + delta] x [0, height]`` overlaps the outer one ``[r_c, r_o] x [0,
    height]`` by the radial interference ``delta`` (not fragmented: no shared nodes);
    ``n`` = segments per cylinder along r and z, structured.

    Groups: bodies ``inner``, ``outer``; edges ``inner_surface`` (r = r_c + delta),
    ``outer_surface`` (r = r_c), ``inner_bottom``, ``inner_top``, ``outer_bottom``,
    ``outer_top``.
    """
    def build():
        occ = gmsh.model.occ
        inner = occ.addRectangle(r_i, 0, 0, r_c + delta - r_i, height)
        outer = occ.addRectangle(r_c, 0, 0, r_o - r_c, height)
        occ.synchronize()
        for s in (inner, outer):
            _transfinite_rectangle(s, n, quads)
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(order)
        group(2, [inner], "inner")
        group(2, [outer], "outer")
        group(1, boundary(2, inner, 0, r_c + delta), "inner_surface")
        group(1, boundary(2, outer, 0, r_c), "outer_surface")
        for s, name in ((inner, "inner"), (outer, "outer")):
            group(1, boundary(2, s, 1, 0.0), f"{name}_bottom")
            group(1, boundary(2, s, 1, height), f"{name}_top")
    return write_model(build, path, comm)


def sphere_section(path: Path, R: float = 10.0, h_contact: float = 0.12,
                   h_far: float = 2.0, refine_radius: float = 1.8, order: int = 1,
                   comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """Meridian section (r = x, z = y) of the lower half of a sphere of radius ``R``,
    centre ``(0, R)``: the quarter disk ``x >= 0, y <= R``, triangles of size ``h_contact``
    within ``refine_radius`` of the pole (0, 0), growing to ``h_far`` 10 further out.

    Groups: body ``sphere``; edges ``sphere_surface`` (the arc), ``sphere_top`` (y = R),
    ``sphere_axis`` (x = 0).
    """
    def build():
        occ = gmsh.model.occ
        disk = occ.addDisk(0, R, 0, R, R)
        box = occ.addRectangle(0, 0, 0, R, R)
        (quarter,), _ = occ.intersect([(2, disk)], [(2, box)])
        occ.synchronize()
        s = quarter[1]
        curves = [t for _, t in gmsh.model.getBoundary([quarter], oriented=False)]
        centres = {c: occ.getCenterOfMass(1, c) for c in curves}
        axis = [c for c in curves if abs(centres[c][0]) < 1e-9]
        top = [c for c in curves if abs(centres[c][1] - R) < 1e-9]
        arc = [c for c in curves if c not in axis + top]
        pole = [t for _, t in gmsh.model.getEntitiesInBoundingBox(
            -1e-6, -1e-6, -1e-6, 1e-6, 1e-6, 1e-6, 0)]
        f = gmsh.model.mesh.field
        dist = f.add("Distance")
        f.setNumbers(dist, "PointsList", pole)
        thr = f.add("Threshold")
        f.setNumber(thr, "InField", dist)
        for key, value in (("SizeMin", h_contact), ("SizeMax", h_far),
                           ("DistMin", refine_radius), ("DistMax", refine_radius + 10.0)):
            f.setNumber(thr, key, value)
        f.setAsBackgroundMesh(thr)
        for key in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints",
                    "Mesh.MeshSizeFromCurvature"):
            gmsh.option.setNumber(key, 0)
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(order)
        group(2, [s], "sphere")
        group(1, arc, "sphere_surface")
        group(1, top, "sphere_top")
        group(1, axis, "sphere_axis")
    return write_model(build, path, comm)


def ring_section(path: Path, R: float = 5.0, c: float = 1.0, h: float = 0.1,
                 comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """Meridian section (r = x, z = y) of the upper half of an O-ring: the half disk of
    radius ``c`` (the cord) centred at ``(R, 0)``, ``y >= 0``, triangles of size ``h``.

    Groups: body ``ring``; edges ``ring_surface`` (the arc), ``ring_equator`` (y = 0).
    """
    def build():
        occ = gmsh.model.occ
        disk = occ.addDisk(R, 0, 0, c, c)
        box = occ.addRectangle(R - c, 0, 0, 2 * c, c)
        (half,), _ = occ.intersect([(2, disk)], [(2, box)])
        occ.synchronize()
        curves = [t for _, t in gmsh.model.getBoundary([half], oriented=False)]
        equator = [t for t in curves if abs(occ.getCenterOfMass(1, t)[1]) < 1e-9]
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.model.mesh.generate(2)
        group(2, [half[1]], "ring")
        group(1, [t for t in curves if t not in equator], "ring_surface")
        group(1, equator, "ring_equator")
    return write_model(build, path, comm)


def block_on_foundation(path: Path, n_slave: int = 8, ratio: float = 1.0, y0: float = 0.0,
                        x_start: float = -0.5, x_end: float = 2.75, shift: float = 0.37,
                        comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """2D: a block [0, 1] x [y0, y0 + 0.5] over a foundation [x_start, x_end] x [-0.5, 0],
    structured quadrilaterals.

    ``n_slave`` faces along the block's bottom (slave spacing h_s = 1/n_slave, n_slave/2
    layers, at least 2); the foundation's top spacing is ``h_s / ratio`` (ratio = slave size
    / master size), its grid shifted by ``shift`` faces (x_start moves left by as much) so
    that slave nodes do not start on master nodes.  Groups: ``block``, ``foundation``;
    ``block_bottom``, ``block_top``, ``foundation_top``, ``foundation_bottom``.  The
    stability tests' and maps' sliding block.
    """
    h_s = 1.0 / n_slave
    h_m = h_s / ratio
    x_start = x_start - shift * h_m
    n_m = max(1, round((x_end - x_start) / h_m))

    def build():
        blk, bl = structured_rectangle(0.0, y0, 1.0, 0.5, n_slave, max(2, n_slave // 2))
        fnd, fl = structured_rectangle(x_start, -0.5, x_end - x_start, 0.5, n_m,
                                       max(2, round(0.5 / max(h_m, 0.0625))))
        group(2, [blk], "block")
        group(2, [fnd], "foundation")
        group(1, [bl["bottom"]], "block_bottom")
        group(1, [bl["top"]], "block_top")
        group(1, [fl["top"]], "foundation_top")
        group(1, [fl["bottom"]], "foundation_bottom")
        gmsh.model.mesh.generate(2)
    return write_model(build, path, comm)


def blocks_on_foundation(path: Path, n_foundation: int = 5, n_block: int = 4,
                         tets: bool = False, comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """Block [0.25,0.75]^2 x [0.5,0.75] on foundation [0,1]^2 x [0,0.5] (not fragmented:
    the bodies do not share nodes), structured hexahedra or tetrahedra.

    Groups: ``block``, ``foundation``; ``block_bottom``, ``block_top``,
    ``foundation_top``, ``foundation_bottom``.  The CalculiX comparisons' mesh
    (``tests/verification/test_calculix.py``).
    """
    def build():
        occ = gmsh.model.occ
        f = occ.addBox(0, 0, 0, 1, 1, 0.5)
        b = occ.addBox(0.25, 0.25, 0.5, 0.5, 0.5, 0.25)
        occ.synchronize()
        for vol, n in ((f, n_foundation), (b, n_block)):
            surfaces = gmsh.model.getBoundary([(3, vol)], combined=False, oriented=False)
            for _, curve in gmsh.model.getBoundary(surfaces, combined=False, oriented=False):
                gmsh.model.mesh.setTransfiniteCurve(abs(curve), n + 1)
            for _, s in surfaces:
                gmsh.model.mesh.setTransfiniteSurface(s)
                if not tets:
                    gmsh.model.mesh.setRecombine(2, s)
            gmsh.model.mesh.setTransfiniteVolume(vol)

        def face(vol, z):
            return [t for _, t in gmsh.model.getBoundary([(3, vol)], oriented=False)
                    if abs(occ.getCenterOfMass(2, t)[2] - z) < 1e-9]

        for dim, tags, name in ((3, [f], "foundation"), (3, [b], "block"),
                                (2, face(f, 0.0), "foundation_bottom"),
                                (2, face(f, 0.5), "foundation_top"),
                                (2, face(b, 0.5), "block_bottom"),
                                (2, face(b, 0.75), "block_top")):
            gmsh.model.setPhysicalName(dim, gmsh.model.addPhysicalGroup(dim, tags), name)
        gmsh.model.mesh.generate(3)
    return write_model(build, path, comm)


def ironing(path: Path, length: float = 10.0, height: float = 5.0, radius: float = 2.0,
            x0: float = 3.0, nx: int = 40, ny: int = 6, bias: float = 0.75, n_arc: int = 32,
            thickness: Optional[float] = None, dim: int = 3) -> Path:
    """The plane-strain ironing geometry, structured: one layer of hexahedra (``dim = 3``)
    or its quadrilaterals (``dim = 2``: the same nodes as the hexahedra's face z = 0).

    Block ``[0, length] x [0, height]`` (``nx`` x ``ny`` cells, rows graded by ``bias``
    towards the top), half-disk die of ``radius`` centred at ``(x0, height + radius)``
    with its flat top there, as an O-grid (a core square and three patches under the
    arc, ``n_arc`` faces along the arc); in 3D extruded by one layer of ``thickness``
    (default ``length / nx``) along z.  Groups: ``block``, ``die``; ``block_top``,
    ``block_bottom``, ``die_surface`` (the arc), ``die_top``; in 3D also ``block_faces``
    and ``die_faces`` (z = 0 and z = thickness).
    """
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.model.add("ironing_one_layer" if dim == 3 else "ironing_2d")
        geo = gmsh.model.geo
        t = thickness if thickness is not None else length / nx
        p = [geo.addPoint(0, 0, 0), geo.addPoint(length, 0, 0), geo.addPoint(length, height, 0),
             geo.addPoint(0, height, 0)]
        bottom, right, top, left = (geo.addLine(p[0], p[1]), geo.addLine(p[1], p[2]),
                                    geo.addLine(p[2], p[3]), geo.addLine(p[3], p[0]))
        block = geo.addPlaneSurface([geo.addCurveLoop([bottom, right, top, left])])
        cx, cy, R = x0, height + radius, radius
        s, q = R / 2, R / math.sqrt(2)
        o = geo.addPoint(cx, cy, 0)
        A, B, C, D = (geo.addPoint(cx - R, cy, 0), geo.addPoint(cx - q, cy - q, 0),
                      geo.addPoint(cx + q, cy - q, 0), geo.addPoint(cx + R, cy, 0))
        a, b, c, d = (geo.addPoint(cx - s, cy, 0), geo.addPoint(cx - s, cy - s, 0),
                      geo.addPoint(cx + s, cy - s, 0), geo.addPoint(cx + s, cy, 0))
        arcs = geo.addCircleArc(A, o, B), geo.addCircleArc(B, o, C), geo.addCircleArc(C, o, D)
        Bb, Cc, Dd, Aa = geo.addLine(B, b), geo.addLine(C, c), geo.addLine(D, d), geo.addLine(A, a)
        ab, bc, cd, da = geo.addLine(a, b), geo.addLine(b, c), geo.addLine(c, d), geo.addLine(d, a)
        loops = {"core": [ab, bc, cd, da], "left": [arcs[0], Bb, -ab, -Aa],
                 "bottom": [arcs[1], Cc, -bc, -Bb], "right": [arcs[2], Dd, -cd, -Cc]}
        die = {k: geo.addPlaneSurface([geo.addCurveLoop(v)]) for k, v in loops.items()}
        m = geo.mesh
        m.setTransfiniteCurve(bottom, nx + 1)
        m.setTransfiniteCurve(top, nx + 1)
        m.setTransfiniteCurve(right, ny + 1, "Progression", bias)  # upwards: thinner rows
        m.setTransfiniteCurve(left, ny + 1, "Progression", 1.0 / bias)
        n1 = max(1, n_arc // 4)
        n2 = max(1, n_arc - 2 * n1)
        for curve, n in ((arcs[0], n1), (arcs[2], n1), (ab, n1), (cd, n1), (arcs[1], n2),
                         (bc, n2), (da, n2), (Bb, n1), (Cc, n1), (Dd, n1), (Aa, n1)):
            m.setTransfiniteCurve(curve, n + 1)
        sources = [block, *die.values()]
        for surface in sources:
            m.setTransfiniteSurface(surface)
            m.setRecombine(2, surface)
        # the 2D entities themselves, or (3D) what the extrusion makes of them
        body, side = {x: x for x in sources}, {}
        if dim == 3:
            ext = geo.extrude([(2, x) for x in sources], 0, 0, t, numElements=[1],
                              recombine=True)
            # per source surface: its copy at z = t, the volume, the lateral surfaces
            copies = []
            for k, (src, curves) in enumerate(zip(sources, [[bottom, right, top, left],
                                                             *loops.values()])):
                chunk = ext[6 * k:6 * k + 6]
                copies.append(chunk[0][1])
                body[src] = chunk[1][1]
                for curve, (_, lat) in zip(curves, chunk[2:]):
                    side.setdefault(abs(curve), lat)
        geo.synchronize()

        def group(d, tags, name):
            gmsh.model.setPhysicalName(d, gmsh.model.addPhysicalGroup(d, tags), name)

        def facets(curves):
            return [side.get(abs(c), abs(c)) for c in curves]

        group(dim, [body[block]], "block")
        group(dim, [body[x] for x in die.values()], "die")
        group(dim - 1, facets([top]), "block_top")
        group(dim - 1, facets([bottom]), "block_bottom")
        if dim == 3:
            group(2, [block, copies[0]], "block_faces")
        group(dim - 1, facets(arcs), "die_surface")
        group(dim - 1, facets([Aa, da, Dd]), "die_top")
        if dim == 3:
            group(2, [*die.values(), *copies[1:]], "die_faces")
        gmsh.model.mesh.generate(dim)
        types = list(gmsh.model.mesh.getElementTypes(dim))
        assert types == [5 if dim == 3 else 3], f"not all hexahedra / quadrilaterals: {types}"
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path


def _graded(h_contact: float, h_far: float, refine_radius: float, growth: float) -> None:
    """Element size ``h_contact`` within ``refine_radius`` of the origin, growing linearly
    (slope ``growth``) up to ``h_far``."""
    field = gmsh.model.mesh.field
    fid = field.add("MathEval")
    field.setString(fid, "F", f"Min({h_far}, {h_contact} + {growth} * "
                              f"Max(0, Sqrt(x*x + y*y + z*z) - {refine_radius}))")
    field.setAsBackgroundMesh(fid)
    for key in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints",
                "Mesh.MeshSizeFromCurvature"):
        gmsh.option.setNumber(key, 0)


def quarter_disk(path: Path, R: float = 10.0, h_contact: float = 0.1, h_far: float = 2.0,
                 refine_radius: float = 1.0, growth: float = 0.25, order: int = 1,
                 block: Optional[tuple[float, float]] = None,
                 comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """Quarter disk ``x >= 0``, centre ``(0, R)``, touching ``y = 0`` at the origin;
    quadrilaterals graded from the origin (:func:`quarter_sphere`'s sizes), of geometric
    ``order`` 1 or 2 (2: mid-side nodes on the arc).  Groups: body ``cylinder``; edges
    ``cylinder_surface`` (the arc), ``cylinder_top`` (``y = R``), ``cylinder_symmetry``
    (``x = 0``) -- as ``demos/hertz_cylinder.py``'s.  ``block = (W, D)``: also a block
    ``[0, W] x [-D, 0]`` under it (no node shared, the same sizes), body ``block``, edges
    ``block_top``, ``block_bottom``, ``block_symmetry`` (``x = 0``)."""
    def build():
        geo = gmsh.model.geo
        c, p0, p1 = geo.addPoint(0, R, 0), geo.addPoint(0, 0, 0), geo.addPoint(R, R, 0)
        arc, top, sym = geo.addCircleArc(p0, c, p1), geo.addLine(p1, c), geo.addLine(c, p0)
        disk = geo.addPlaneSurface([geo.addCurveLoop([arc, top, sym])])
        groups = [(2, [disk], "cylinder"), (1, [arc], "cylinder_surface"),
                  (1, [top], "cylinder_top"), (1, [sym], "cylinder_symmetry")]
        if block is not None:
            W, D = block
            q = [geo.addPoint(0, 0, 0), geo.addPoint(0, -D, 0), geo.addPoint(W, -D, 0),
                 geo.addPoint(W, 0, 0)]
            edges = [geo.addLine(q[i], q[(i + 1) % 4]) for i in range(4)]  # x=0, bottom, x=W, top
            under = geo.addPlaneSurface([geo.addCurveLoop(edges)])
            groups += [(2, [under], "block"), (1, [edges[3]], "block_top"),
                       (1, [edges[1]], "block_bottom"), (1, [edges[0]], "block_symmetry")]
        geo.synchronize()
        _graded(h_contact, h_far, refine_radius, growth)
        for key, value in (("Mesh.Algorithm", 6), ("Mesh.RecombineAll", 1),
                           ("Mesh.RecombinationAlgorithm", 1)):
            gmsh.option.setNumber(key, value)
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(order)
        for dim, tags, name in groups:
            group(dim, tags, name)
    return write_model(build, path, comm)


def quarter_sphere(path: Path, R: float = 10.0, h_contact: float = 0.1, h_far: float = 2.0,
                   refine_radius: float = 1.0, growth: float = 0.25, order: int = 1,
                   block: Optional[tuple[float, float]] = None,
                   comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """Quarter of the lower hemisphere ``x, y >= 0``, centre ``(0, 0, R)``, touching
    ``z = 0`` at the origin: tetrahedra of size ``h_contact`` within ``refine_radius`` of
    the origin, growing linearly (slope ``growth``) up to ``h_far``, of geometric ``order``
    1 or 2 (2: mid-edge nodes on the sphere).  Groups: body ``sphere``; facets
    ``sphere_surface`` (the curved surface), ``sphere_top`` (``z = R``),
    ``sphere_symmetry_x`` (``x = 0``), ``sphere_symmetry_y`` (``y = 0``) -- as
    ``demos/hertz_sphere.py``'s.  ``block = (L, D)``: also a quarter block
    ``[0, L]^2 x [-D, 0]`` under it (no node shared, the same sizes), body ``block``,
    facets ``block_top``, ``block_bottom``, ``block_symmetry_x``, ``block_symmetry_y``."""
    def build():
        occ = gmsh.model.occ
        vol = occ.addSphere(0, 0, R, R, angle1=-math.pi / 2, angle2=0.0, angle3=math.pi / 2)
        under = occ.addBox(0, 0, -block[1], block[0], block[0], block[1]) if block else None
        occ.synchronize()
        names: dict[str, list[int]] = {}
        for _, s in gmsh.model.getBoundary([(3, vol)], oriented=False):
            c = occ.getCenterOfMass(2, s)
            name = ("sphere_top" if abs(c[2] - R) < 1e-6 * R else
                    "sphere_symmetry_x" if abs(c[0]) < 1e-6 * R else
                    "sphere_symmetry_y" if abs(c[1]) < 1e-6 * R else "sphere_surface")
            names.setdefault(name, []).append(s)
        if under is not None:
            for name, axis, value in (("block_top", 2, 0.0), ("block_bottom", 2, -block[1]),
                                      ("block_symmetry_x", 0, 0.0),
                                      ("block_symmetry_y", 1, 0.0)):
                names[name] = boundary(3, under, axis, value)
        _graded(h_contact, h_far, refine_radius, growth)
        gmsh.option.setNumber("Mesh.Algorithm", 6)
        gmsh.option.setNumber("Mesh.Algorithm3D", 1)  # Delaunay: the same tetrahedra every run (HXT: not)
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(order)
        group(3, [vol], "sphere")
        if under is not None:
            group(3, [under], "block")
        for name, tags in names.items():
            group(2, tags, name)
    return write_model(build, path, comm)


def stacked(path: Path, n_lower: int, n_upper: int, dim: int = 2, tets: bool = False,
            order: int = 1, comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """Two blocks of the same footprint ``[0,1]^(dim-1)`` stacked on a flat interface
    (the contact patch test): ``lower`` (height 0.5) and ``upper`` (0.5 to 1), structured
    (``n_lower``, ``n_upper`` cells along each side of the interface, half as many across
    each block's height, at least 2), quadrilaterals/hexahedra or with ``tets`` triangles/
    tetrahedra, of geometric ``order`` 1 or 2.  Groups: ``lower``, ``upper``; facets
    ``<body>_bottom``, ``<body>_top``, ``<body>_x0`` (``x = 0``), ``<body>_x1`` (``x = 1``)
    and in 3D ``<body>_y0`` (``y = 0``)."""
    def build():
        occ = gmsh.model.occ
        bodies = {}
        for name, z0, n in (("lower", 0.0, n_lower), ("upper", 0.5, n_upper)):
            if dim == 2:
                tag = occ.addRectangle(0, z0, 0, 1, 0.5)
            else:
                tag = occ.addBox(0, 0, z0, 1, 1, 0.5)
            bodies[name] = (tag, n, z0)
        occ.synchronize()
        up = dim - 1  # the stacking axis
        for name, (tag, n, z0) in bodies.items():
            faces = gmsh.model.getBoundary([(dim, tag)], oriented=False)
            edges = (faces if dim == 2 else
                     gmsh.model.getBoundary(faces, combined=False, oriented=False))
            for _, curve in edges:
                a, b = gmsh.model.getBoundary([(1, abs(curve))], oriented=False)
                pa, pb = gmsh.model.getValue(0, a[1], []), gmsh.model.getValue(0, b[1], [])
                across = abs(pa[up] - pb[up]) > 1e-9
                gmsh.model.mesh.setTransfiniteCurve(abs(curve),
                                                    (max(n // 2, 2) if across else n) + 1)
            for _, s in (faces if dim == 3 else [(2, tag)]):
                gmsh.model.mesh.setTransfiniteSurface(s)
                if not tets:
                    gmsh.model.mesh.setRecombine(2, s)
            if dim == 3:
                gmsh.model.mesh.setTransfiniteVolume(tag)
            group(dim, [tag], name)
            group(dim - 1, boundary(dim, tag, up, z0), f"{name}_bottom")
            group(dim - 1, boundary(dim, tag, up, z0 + 0.5), f"{name}_top")
            group(dim - 1, boundary(dim, tag, 0, 0.0), f"{name}_x0")
            group(dim - 1, boundary(dim, tag, 0, 1.0), f"{name}_x1")
            if dim == 3:
                group(dim - 1, boundary(dim, tag, 1, 0.0), f"{name}_y0")
        gmsh.model.mesh.generate(dim)
        gmsh.model.mesh.setOrder(order)
    return write_model(build, path, comm)


def rolling_layer(path: Path, width: float = 2.0, depth: float = 1.0,
                  track: tuple[float, float] = (0.6, 1.4), h_track: float = 0.01,
                  h_far: float = 0.2, order: int = 2, comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """Elastic layer [0, width] x [-depth, 0] for a rigid wheel rolling on its top: triangles
    of size ``h_track`` along the top edge over ``track`` (x from, to), growing to ``h_far``
    away from it; ``order`` 1 or 2.  Body ``block``, edges ``top``, ``bottom``, ``left``,
    ``right``.  Written by rank 0 of ``comm``."""
    def build():
        s = gmsh.model.occ.addRectangle(0, -depth, 0, width, depth)
        gmsh.model.occ.synchronize()
        f = gmsh.model.mesh.field
        band = f.add("Box")
        f.setNumber(band, "VIn", h_track)
        f.setNumber(band, "VOut", h_far)
        f.setNumber(band, "XMin", track[0])
        f.setNumber(band, "XMax", track[1])
        f.setNumber(band, "YMin", -5 * h_track)
        f.setNumber(band, "YMax", 0.0)
        f.setNumber(band, "Thickness", 0.3 * depth)
        f.setAsBackgroundMesh(band)
        for key in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
            gmsh.option.setNumber(f"Mesh.{key}", 0)
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(order)
        group(2, [s], "block")
        group(1, boundary(2, s, 1, 0.0), "top")
        group(1, boundary(2, s, 1, -depth), "bottom")
        group(1, boundary(2, s, 0, 0.0), "left")
        group(1, boundary(2, s, 0, width), "right")
    return write_model(build, path, comm)
