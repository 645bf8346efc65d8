"""Meshes of the benchmarks that no demo provides (built with gmsh on the calling rank).

* :func:`quarter_sphere` -- a quarter of the lower hemisphere of a sphere of radius ``R``
  resting on ``z = 0``, tetrahedra refined around the first contact point.  Written
  because ``demos/hertz_sphere.py`` did not exist when ``bench_hertz.py`` was written;
  that demo's ``build_mesh`` (same geometry and group names) is now used, this one only
  if the demo is missing.
* :func:`two_boxes` -- ``reference.meshes.two_boxes`` (block on a foundation, structured
  hexahedra) at a resolution given by one integer, with a foundation mesh chosen so that
  no slave node lies on an edge of a master face (there the choice of master face is
  arbitrary, and CalculiX with tight controls can stall switching faces).
* :func:`one_layer` -- a 2D quadrilateral mesh extruded by one layer of hexahedra (the 3D
  twin of a plane-strain scene, for CalculiX, which has no 2D export): every 2D group keeps
  its name one dimension up, ``<body>_faces`` are the two faces z = 0 and z = thickness.
"""
from __future__ import annotations

import math
from pathlib import Path

from _bench import ROOT  # noqa: F401  (sys.path)


def quarter_sphere(path: Path, R: float = 10.0, h_contact: float = 0.1, h_far: float = 2.0,
                   refine_radius: float = 1.0, growth: float = 0.25, order: int = 1) -> Path:
    """Quarter lower hemisphere ``x, y >= 0``, centre ``(0, 0, R)``, touching ``z = 0`` at the origin.

    Tetrahedra of size ``h_contact`` within ``refine_radius`` of the origin, growing
    linearly (slope ``growth``) up to ``h_far``.  Groups: body ``sphere``; facets
    ``sphere_surface`` (the curved surface), ``sphere_top`` (``z = R``),
    ``sphere_symmetry_x`` (``x = 0``), ``sphere_symmetry_y`` (``y = 0``) -- as the demo's.
    """
    import gmsh
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("quarter_sphere")
        occ = gmsh.model.occ
        vol = occ.addSphere(0, 0, R, R, angle1=-math.pi / 2, angle2=0.0, angle3=math.pi / 2)
        occ.synchronize()
        names = {}
        for _, s in gmsh.model.getBoundary([(3, vol)], oriented=False):
            c = occ.getCenterOfMass(2, s)
            if abs(c[2] - R) < 1e-6 * R:
                names.setdefault("sphere_top", []).append(s)
            elif abs(c[0]) < 1e-6 * R:
                names.setdefault("sphere_symmetry_x", []).append(s)
            elif abs(c[1]) < 1e-6 * R:
                names.setdefault("sphere_symmetry_y", []).append(s)
            else:
                names.setdefault("sphere_surface", []).append(s)
        f = gmsh.model.mesh.field
        fid = f.add("MathEval")
        f.setString(fid, "F", f"Min({h_far}, {h_contact} + {growth} * "
                              f"Max(0, Sqrt(x*x + y*y + z*z) - {refine_radius}))")
        f.setAsBackgroundMesh(fid)
        for key, value in (("Mesh.MeshSizeExtendFromBoundary", 0), ("Mesh.MeshSizeFromPoints", 0),
                           ("Mesh.MeshSizeFromCurvature", 0), ("Mesh.Algorithm", 6),
                           ("Mesh.Algorithm3D", 10)):
            gmsh.option.setNumber(key, value)
        gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [vol]), "sphere")
        for name, tags in names.items():
            gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, tags), name)
        gmsh.model.mesh.generate(3)
        if order > 1:
            gmsh.model.mesh.setOrder(order)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path


def foundation_divisions(n: int) -> int:
    """Foundation cells per side (about 1.5x the block's density) with every slave node at
    least 15 % of a master face away from the master grid lines."""
    block = [0.25 + 0.5 * i / (2 * n) for i in range(2 * n + 1)]
    best = None
    for m in range(3 * n + 1, 3 * n + 12):
        gap = min(min(abs(x * m - round(x * m)) for x in block), 1.0)
        if gap >= 0.15:
            return m
        if best is None or gap > best[0]:
            best = (gap, m)
    return best[1]


def two_boxes_dofs(n: int) -> int:
    m = foundation_divisions(n)
    return 3 * ((2 * n + 1) ** 2 * (n + 1) + (m + 1) ** 2 * (n + 1))


def two_boxes(path: Path, n: int) -> Path:
    """Block 2n x 2n x n hexahedra on a foundation m x m x n (:func:`foundation_divisions`)."""
    from dolfinx_friction.reference.meshes import two_boxes as build
    m = foundation_divisions(n)
    return build(path, (2 * n, 2 * n, n), (m, m, n))


def n_for_dofs(target: float) -> int:
    """Smallest ``n`` whose two_boxes mesh has at least ``target`` dofs."""
    n = 1
    while two_boxes_dofs(n) < target:
        n += 1
    return n


def one_layer(source: Path, path: Path, thickness: float) -> Path:
    """Extrude the 2D quadrilateral mesh ``source`` (gmsh, physical surfaces = bodies,
    physical curves = facet groups) by one layer of hexahedra of ``thickness`` along z.

    The same nodes in both planes z = 0 and z = thickness; a body ``b`` becomes a volume
    group ``b``, a curve group a surface group of the same name, and ``b_faces`` holds the
    body's quadrilaterals in both planes (for ``u_z = 0``: plane strain).
    """
    import gmsh
    import numpy as np
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.open(str(source))
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        xyz = xyz.reshape(-1, 3)
        n = int(tags.max())
        coords = np.zeros((n, 3))
        coords[tags.astype(int) - 1] = xyz

        def elements(dim, group, etype):
            out = [gmsh.model.mesh.getElements(dim, e) for e in
                   gmsh.model.getEntitiesForPhysicalGroup(dim, group)]
            nodes = [nt[list(t).index(etype)] for t, _, nt in out if etype in list(t)]
            width = 4 if etype == 3 else 2
            return np.concatenate(nodes).astype(np.int64).reshape(-1, width)

        bodies = {gmsh.model.getPhysicalName(2, g): elements(2, g, 3)
                  for _, g in gmsh.model.getPhysicalGroups(2)}
        curves = {gmsh.model.getPhysicalName(1, g): elements(1, g, 1)
                  for _, g in gmsh.model.getPhysicalGroups(1)}
        gmsh.model.remove()
        gmsh.model.add("one_layer")
        top = np.column_stack([coords[:, :2], np.full(n, float(thickness))])
        entity = 0

        def add(dim, etype, conn, name):
            nonlocal entity
            entity += 1
            gmsh.model.addDiscreteEntity(dim, entity)
            gmsh.model.mesh.addElementsByType(entity, etype, [], conn.ravel().tolist())
            gmsh.model.setPhysicalName(dim, gmsh.model.addPhysicalGroup(dim, [entity]), name)

        gmsh.model.addDiscreteEntity(3, 10 ** 6)
        bottom = np.column_stack([coords[:, :2], np.zeros(n)])
        gmsh.model.mesh.addNodes(3, 10 ** 6, np.arange(1, 2 * n + 1).tolist(),
                                 np.concatenate([bottom.ravel(), top.ravel()]).tolist())
        for name, quads in bodies.items():
            x = coords[quads - 1, :2]
            area = np.sum(x[:, :, 0] * np.roll(x[:, :, 1], -1, 1)
                          - np.roll(x[:, :, 0], -1, 1) * x[:, :, 1], axis=1)
            quads = np.where((area > 0)[:, None], quads, quads[:, ::-1])  # counter-clockwise
            add(3, 5, np.hstack([quads, quads + n]), name)
            add(2, 3, np.vstack([quads[:, ::-1], quads + n]), f"{name}_faces")
        for name, lines in curves.items():
            add(2, 3, np.column_stack([lines, lines[:, ::-1] + n]), name)
        gmsh.model.mesh.reclassifyNodes()
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path
