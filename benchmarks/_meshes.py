"""Meshes of the benchmarks that no demo provides (built with gmsh on the calling rank).

* :func:`quarter_sphere` -- ``reference.meshes.quarter_sphere``: a quarter of the lower
  hemisphere of a sphere of radius ``R`` resting on ``z = 0``, tetrahedra refined around
  the first contact point; ``demos/hertz_sphere.py``'s ``build_mesh`` (same geometry and
  group names) is used, this one only if the demo is missing.
* :func:`two_boxes` -- ``reference.meshes.two_boxes`` (block on a foundation, structured
  hexahedra) at a resolution given by one integer, with a foundation mesh chosen so that
  no slave node lies on an edge of a master face (there the choice of master face is
  arbitrary, and CalculiX with tight controls can stall switching faces).
* :func:`one_layer` -- a 2D quadrilateral mesh extruded by one layer of hexahedra (the 3D
  twin of a plane-strain scene, for CalculiX, which has no 2D export): every 2D group keeps
  its name one dimension up, ``<body>_faces`` are the two faces z = 0 and z = thickness.
"""
from __future__ import annotations

from pathlib import Path

from _bench import ROOT  # noqa: F401  (sys.path)

from dolfinx_friction.reference.meshes import quarter_sphere  # noqa: F401  (re-exported)


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
