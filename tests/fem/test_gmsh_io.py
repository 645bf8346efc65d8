"""dolfinx_friction.io.gmsh: Gmsh meshes -> one dolfinx mesh per body.

Runs serially and under ``mpirun -n 2``: Gmsh models are built on rank 0
only (files go to a directory broadcast from rank 0); every rank calls
``load_mesh`` and checks global (summed) quantities.
"""
from __future__ import annotations

import contextlib
import os
import re
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

gmsh = pytest.importorskip("gmsh")
dolfinx = pytest.importorskip("dolfinx")
import basix  # noqa: E402
import ufl  # noqa: E402

from dolfinx_friction import _compat as compat  # noqa: E402
from dolfinx_friction.io.gmsh import BodyMesh, MeshError, MeshSet, load_mesh  # noqa: E402
from dolfinx_friction.io.msh import gmsh_initialized  # noqa: E402

comm = MPI.COMM_WORLD
ROOT = comm.rank == 0
N = 4  # points per box edge (3 segments)


# --------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------
@pytest.fixture
def shared_dir():
    """A temporary directory created on rank 0 and known to all ranks."""
    path = comm.bcast(tempfile.mkdtemp(prefix="gmsh_io_") if ROOT else None, root=0)
    yield Path(path)
    comm.barrier()
    if ROOT:
        shutil.rmtree(path, ignore_errors=True)


@contextlib.contextmanager
def gmsh_session():
    """gmsh initialized for the block (rank 0 only), finalized afterwards."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        yield
    finally:
        gmsh.finalize()


def on_root(fn, *args, **kwargs):
    """Run fn on rank 0 and broadcast its result (an exception is broadcast too)."""
    result = None
    if ROOT:
        try:
            result = ("ok", fn(*args, **kwargs))
        except Exception as e:  # pragma: no cover - test set-up bug
            result = ("err", repr(e))
    result = comm.bcast(result, root=0)
    if result[0] == "err":
        raise RuntimeError(f"rank 0 set-up failed: {result[1]}")
    return result[1]


def entities(dim, pred):
    """Gmsh entities of dimension dim whose bounding box (lo, hi) satisfies pred."""
    out = []
    for _, tag in gmsh.model.getEntities(dim):
        bb = np.array(gmsh.model.getBoundingBox(dim, tag))
        if pred(bb[:3], bb[3:]):
            out.append(tag)
    return out


def group(dim, tags, name):
    assert tags, name
    t = gmsh.model.addPhysicalGroup(dim, tags)
    gmsh.model.setPhysicalName(dim, t, name)


def num_elements(dim, name):
    """Number of mesh elements of the named physical group of dim (rank 0)."""
    for d, t in gmsh.model.getPhysicalGroups(dim):
        if gmsh.model.getPhysicalName(d, t) == name:
            return sum(sum(len(e) for e in gmsh.model.mesh.getElements(d, ent)[1])
                       for ent in gmsh.model.getEntitiesForPhysicalGroup(d, t))
    raise KeyError(name)


def num_nodes(dim, name):
    for d, t in gmsh.model.getPhysicalGroups(dim):
        if gmsh.model.getPhysicalName(d, t) == name:
            return len(gmsh.model.mesh.getNodesForPhysicalGroup(d, t)[0])
    raise KeyError(name)


def build_boxes(cell: str, order: int):
    """lower = [0,1]^3, upper = [0,1]^2 x [1,1.5], fragmented (conforming) mesh.

    Groups: bodies lower/upper, facets interface (z=1), bottom (z=0), top
    (z=1.5), left (x=0, both bodies), upper_left (x=0, upper only), edges
    top_edges (the 4 edges at z=1.5), points top_corners (4 corners at z=1.5).
    """
    gmsh.model.add(f"boxes_{cell}{order}")
    occ = gmsh.model.occ
    a = occ.addBox(0, 0, 0, 1, 1, 1)
    b = occ.addBox(0, 0, 1, 1, 1, 0.5)
    occ.fragment([(3, a)], [(3, b)])
    occ.synchronize()
    eps = 1e-6
    group(3, entities(3, lambda lo, hi: hi[2] < 1 + eps), "lower")
    group(3, entities(3, lambda lo, hi: lo[2] > 1 - eps), "upper")
    flat = lambda z: (lambda lo, hi: abs(lo[2] - z) < eps and abs(hi[2] - z) < eps)  # noqa: E731
    group(2, entities(2, flat(1.0)), "interface")
    group(2, entities(2, flat(0.0)), "bottom")
    group(2, entities(2, flat(1.5)), "top")
    group(2, entities(2, lambda lo, hi: abs(hi[0]) < eps), "left")
    group(2, entities(2, lambda lo, hi: abs(hi[0]) < eps and lo[2] > 1 - eps), "upper_left")
    group(1, entities(1, flat(1.5)), "top_edges")
    group(0, entities(0, flat(1.5)), "top_corners")
    for _, t in gmsh.model.getEntities(1):
        gmsh.model.mesh.setTransfiniteCurve(t, N)
    if cell == "hex":
        for _, t in gmsh.model.getEntities(2):
            gmsh.model.mesh.setTransfiniteSurface(t)
            gmsh.model.mesh.setRecombine(2, t)
        for _, t in gmsh.model.getEntities(3):
            gmsh.model.mesh.setTransfiniteVolume(t)
    gmsh.model.mesh.generate(3)
    if order == 2:
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
        gmsh.model.mesh.setOrder(2)
    return {
        "cells": {b: num_elements(3, b) for b in ("lower", "upper")},
        "nodes": {b: num_nodes(3, b) for b in ("lower", "upper")},
        "total_nodes": len(np.unique(gmsh.model.mesh.getNodes()[0])),
        "interface_nodes": num_nodes(2, "interface"),
    }


def build_2d(cell: str, order: int, incomplete: bool = False):
    """plate = [-2,2]x[-2,-1.5] and disk = circle(0, 0, r=1), separate bodies.

    Groups: plate, disk, plate_bottom (y=-2), rim (the circle), corner (point
    (-2,-2)).
    """
    gmsh.model.add(f"plane_{cell}{order}")
    occ = gmsh.model.occ
    plate = occ.addRectangle(-2, -2, 0, 4, 0.5)
    disk = occ.addDisk(0, 0, 0, 1, 1)
    occ.synchronize()
    group(2, [plate], "plate")
    group(2, [disk], "disk")
    eps = 1e-6
    group(1, entities(1, lambda lo, hi: abs(hi[1] + 2) < eps), "plate_bottom")
    rim = [t for _, t in gmsh.model.getBoundary([(2, disk)], oriented=False)]
    group(1, rim, "rim")
    group(0, entities(0, lambda lo, hi: np.allclose(lo[:2], [-2, -2])), "corner")
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.25)
    if cell == "quad":
        gmsh.option.setNumber("Mesh.RecombineAll", 1)
        gmsh.option.setNumber("Mesh.SubdivisionAlgorithm", 1)  # quads only
    gmsh.model.mesh.generate(2)
    if order == 2:
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1 if incomplete else 0)
        gmsh.model.mesh.setOrder(2)
    return {b: num_elements(2, b) for b in ("plate", "disk")}


def write(path: Path, version: float = 4.1):
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.write(str(path))


def owned(body: BodyMesh, name: str) -> np.ndarray:
    dim, idx = body.groups[name]
    return idx[idx < body.mesh.topology.index_map(dim).size_local]


def global_count(body: BodyMesh, name: str) -> int:
    return comm.allreduce(len(owned(body, name)), op=MPI.SUM)


def num_cells(body: BodyMesh) -> int:
    tdim = body.mesh.topology.dim
    return body.mesh.topology.index_map(tdim).size_global


def integrate(mesh, measure) -> float:
    one = compat.scalar_constant(mesh, 1.0)
    return comm.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(one * measure)), op=MPI.SUM)


def group_measures(body: BodyMesh, dim: int, names: list[str]) -> dict[str, float]:
    """Total size (length/area) of each named facet group of a body."""
    tags, values = body.meshtags(dim, names)
    ds = ufl.Measure("ds", domain=body.mesh, subdomain_data=tags)
    return {n: integrate(body.mesh, ds(v)) for n, v in values.items()}


def node_coords(body: BodyMesh) -> np.ndarray:
    g = body.mesh.geometry
    return g.x[: g.index_map().size_local, : g.dim]


def check_node_order(body: BodyMesh):
    """Every cell's nodes are where the (multi)linear map of its vertices puts
    dolfinx's reference nodes: catches a wrong gmsh -> dolfinx permutation
    (valid for the straight-sided cells used here)."""
    g = body.mesh.geometry
    cell = getattr(basix.CellType, body.mesh.topology.cell_name())
    degree = compat.geometry_degree(body.mesh)
    dofmap = compat.geometry_dofmap(body.mesh)
    tdim = body.mesh.topology.dim
    dofmap = np.asarray(dofmap).reshape(body.mesh.topology.index_map(tdim).size_local, -1)
    ref = basix.create_element(basix.ElementFamily.P, cell, degree,
                               basix.LagrangeVariant.equispaced).points
    p1 = basix.create_element(basix.ElementFamily.P, cell, 1)
    shape = p1.tabulate(0, ref)[0, :, :, 0]  # (nodes, vertices)
    nv = shape.shape[1]
    x = g.x[:, : g.dim]
    for nodes in dofmap:
        np.testing.assert_allclose(x[nodes], shape @ x[nodes[:nv]], atol=1e-10)


# --------------------------------------------------------------------------
# 3D: two boxes, fragmented
# --------------------------------------------------------------------------
@pytest.mark.parametrize("cell,order", [("hex", 1), ("tet", 1), ("hex", 2), ("tet", 2)])
def test_two_boxes_live_model(cell, order):
    with contextlib.ExitStack() as stack:
        if ROOT:
            stack.enter_context(gmsh_session())
        info = on_root(build_boxes, cell, order)
        ms = load_mesh(gmsh, ["lower", "upper"], comm)
        if ROOT:  # a live model is left alone
            assert gmsh_initialized(gmsh)
            assert gmsh.model.getCurrent() == f"boxes_{cell}{order}"
    check_boxes(ms, info, cell, order)


def check_boxes(ms: MeshSet, info: dict, cell: str, order: int):
    assert isinstance(ms, MeshSet) and ms.gdim == 3
    assert list(ms.bodies) == ["lower", "upper"]
    assert ms.group_dims == {"lower": 3, "upper": 3, "interface": 2, "bottom": 2, "top": 2,
                             "left": 2, "upper_left": 2, "top_edges": 1, "top_corners": 0}
    assert ms.group_bodies == {"lower": ("lower",), "upper": ("upper",),
                               "interface": ("lower", "upper"), "bottom": ("lower",),
                               "top": ("upper",), "left": (), "upper_left": ("upper",),
                               "top_edges": ("upper",), "top_corners": ("upper",)}
    lower, upper = ms.bodies["lower"], ms.bodies["upper"]
    assert set(lower.groups) == {"lower", "interface", "bottom"}
    assert set(upper.groups) == {"upper", "interface", "top", "upper_left", "top_edges",
                                 "top_corners"}
    expected_type = {"hex": "hexahedron", "tet": "tetrahedron"}[cell]
    for name, body in ms.bodies.items():
        assert body.name == name
        assert body.mesh.topology.cell_name() == expected_type
        assert compat.geometry_degree(body.mesh) == order
        assert body.mesh.geometry.dim == 3
        # total cells (sum over ranks) = the body's gmsh elements
        assert num_cells(body) == info["cells"][name]
        assert global_count(body, name) == info["cells"][name]
        # distributed over the ranks, without ghost cells (GhostMode.none)
        cell_map = body.mesh.topology.index_map(3)
        assert cell_map.num_ghosts == 0
        assert cell_map.size_local > 0
        # each mesh is made of its own cells' nodes only
        assert body.mesh.geometry.index_map().size_global == info["nodes"][name]
        for dim, idx in body.groups.values():
            assert idx.dtype == np.int32
            assert np.all(np.diff(idx) > 0)
        check_node_order(body)
    # the two bodies do not share nodes: the interface nodes exist twice
    assert info["nodes"]["lower"] + info["nodes"]["upper"] == \
        info["total_nodes"] + info["interface_nodes"]
    z_lo = comm.allreduce(node_coords(upper)[:, 2].min(initial=np.inf), op=MPI.MIN)
    z_hi = comm.allreduce(node_coords(lower)[:, 2].max(initial=-np.inf), op=MPI.MAX)
    assert z_lo == pytest.approx(1.0) and z_hi == pytest.approx(1.0)

    # facet groups: areas
    assert group_measures(lower, 2, ["interface", "bottom"]) == \
        pytest.approx({"interface": 1.0, "bottom": 1.0}, rel=1e-10)
    assert group_measures(upper, 2, ["interface", "top", "upper_left"]) == \
        pytest.approx({"interface": 1.0, "top": 1.0, "upper_left": 0.5}, rel=1e-10)
    # volumes
    assert integrate(lower.mesh, ufl.dx(domain=lower.mesh)) == pytest.approx(1.0, rel=1e-10)
    assert integrate(upper.mesh, ufl.dx(domain=upper.mesh)) == pytest.approx(0.5, rel=1e-10)

    # edge group: 4 edges of N-1 segments at z = 1.5, on the top square's perimeter
    assert upper.groups["top_edges"][0] == 1
    assert global_count(upper, "top_edges") == 4 * (N - 1)
    mid = dolfinx.mesh.compute_midpoints(upper.mesh, 1, owned(upper, "top_edges"))
    assert np.allclose(mid[:, 2], 1.5)
    on_side = np.isclose(mid[:, 0], 0) | np.isclose(mid[:, 0], 1) | \
        np.isclose(mid[:, 1], 0) | np.isclose(mid[:, 1], 1)
    assert on_side.all()
    # point group: the 4 top corners
    assert upper.groups["top_corners"][0] == 0
    assert global_count(upper, "top_corners") == 4
    pts = dolfinx.mesh.compute_midpoints(upper.mesh, 0, owned(upper, "top_corners"))
    pts = np.concatenate(comm.allgather(np.asarray(pts).reshape(-1, 3)))
    corners = {(0, 0), (0, 1), (1, 0), (1, 1)}
    assert {tuple(np.round(p[:2]).astype(int)) for p in pts} == corners
    assert np.allclose(pts[:, 2], 1.5)

    # meshtags: values follow the order of names, overlap / wrong dim refused
    tags, values = upper.meshtags(2, ["top", "interface"])
    assert values == {"top": 1, "interface": 2}
    assert tags.dim == 2
    assert np.array_equal(np.sort(tags.indices[tags.values == 1]), upper.groups["top"][1])
    with pytest.raises(ValueError, match="overlap"):
        upper.meshtags(2, ["top", "top"])
    with pytest.raises(ValueError, match="top_edges"):
        upper.meshtags(2, ["top_edges"])
    with pytest.raises(KeyError, match="bottom"):
        upper.meshtags(2, ["bottom"])


@pytest.mark.parametrize("version", [2.2, 4.1])
def test_msh_versions(shared_dir, version):
    path = shared_dir / f"boxes_{version}.msh"

    def make():
        with gmsh_session():
            info = build_boxes("tet", 1)
            write(path, version)
            return info

    info = on_root(make)
    ms = load_mesh(path, ["lower", "upper"], comm)
    if ROOT:
        assert not gmsh_initialized(gmsh)  # initialized by load_mesh -> finalized again
    check_boxes(ms, info, "tet", 1)


def test_file_keeps_user_gmsh_session(shared_dir):
    path = shared_dir / "boxes.msh"
    with contextlib.ExitStack() as stack:
        if ROOT:
            stack.enter_context(gmsh_session())
            build_boxes("hex", 1)
            write(path)
            gmsh.model.add("mine")
            gmsh.option.setNumber("General.Terminal", 1)
            models = sorted(gmsh.model.list())
        comm.barrier()
        ms = load_mesh(str(path), ["lower", "upper"], comm)
        if ROOT:
            assert gmsh_initialized(gmsh)
            assert gmsh.model.getCurrent() == "mine"
            assert sorted(gmsh.model.list()) == models
            assert gmsh.option.getNumber("General.Terminal") == 1
            gmsh.option.setNumber("General.Terminal", 0)
    assert num_cells(ms.bodies["upper"]) == (N - 1) ** 3


# --------------------------------------------------------------------------
# 2D
# --------------------------------------------------------------------------
@pytest.mark.parametrize("cell,order", [("tri", 1), ("quad", 1), ("tri", 2), ("quad", 2)])
def test_2d(shared_dir, cell, order):
    path = shared_dir / "plane.msh"

    def make():
        with gmsh_session():
            counts = build_2d(cell, order)
            write(path)
            return counts

    counts = on_root(make)
    ms = load_mesh(path, ["plate", "disk"], comm)
    assert ms.gdim == 2
    assert ms.group_dims == {"plate": 2, "disk": 2, "plate_bottom": 1, "rim": 1, "corner": 0}
    assert ms.group_bodies == {"plate": ("plate",), "disk": ("disk",), "plate_bottom": ("plate",),
                               "rim": ("disk",), "corner": ("plate",)}
    expected_type = {"tri": "triangle", "quad": "quadrilateral"}[cell]
    for name, body in ms.bodies.items():
        assert body.mesh.topology.cell_name() == expected_type
        assert body.mesh.geometry.dim == 2
        assert compat.geometry_degree(body.mesh) == order
        assert num_cells(body) == counts[name]
    plate, disk = ms.bodies["plate"], ms.bodies["disk"]
    check_node_order(plate)
    assert integrate(plate.mesh, ufl.dx(domain=plate.mesh)) == pytest.approx(2.0, rel=1e-10)
    bottom = group_measures(plate, 1, ["plate_bottom"])["plate_bottom"]
    assert bottom == pytest.approx(4.0, rel=1e-10)
    area = integrate(disk.mesh, ufl.dx(domain=disk.mesh))
    rim = group_measures(disk, 1, ["rim"])["rim"]
    tol = {1: 2e-2, 2: 2e-4}[order]  # second-order geometry follows the circle
    assert area == pytest.approx(np.pi, rel=tol)
    assert rim == pytest.approx(2 * np.pi, rel=tol)
    assert global_count(plate, "corner") == 1
    pts = dolfinx.mesh.compute_midpoints(plate.mesh, 0, owned(plate, "corner"))
    pts = np.concatenate(comm.allgather(np.asarray(pts).reshape(-1, 3)))
    assert np.allclose(pts[:, :2], [[-2, -2]])


# --------------------------------------------------------------------------
# errors: MeshError on every rank, naming the file / group
# --------------------------------------------------------------------------
def expect_error(source, bodies, match):
    with pytest.raises(MeshError, match=match):
        load_mesh(source, bodies, comm)
    comm.barrier()


def test_missing_file(shared_dir):
    expect_error(shared_dir / "nope.msh", ["a"], r"nope\.msh.*does not exist")


def test_corrupt_file(shared_dir):
    path = shared_dir / "corrupt.msh"
    if ROOT:
        path.write_text("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\ngarbage\n")
    comm.barrier()
    expect_error(path, ["a"], r"corrupt\.msh.*cannot be read")
    if ROOT:
        assert not gmsh_initialized(gmsh)


def test_geo_script_is_not_run(shared_dir):
    """A .geo script saved as .msh is refused before gmsh reads it: its SystemCall never runs."""
    path, marker = shared_dir / "script.msh", shared_dir / "ran"
    if ROOT:
        path.write_text(f'SystemCall "touch {marker}";\nPoint(1) = {{0, 0, 0, 1}};\n')
    comm.barrier()
    expect_error(path, ["a"], r"script\.msh.*not Gmsh MSH 2\.2 or 4\.1")
    assert not marker.exists()


def test_options_file_beside_mesh_is_not_run(boxes_file):
    """gmsh would merge ``<mesh>.opt`` (a script) found beside the mesh: it must not."""
    marker = boxes_file.parent / "ran"
    if ROOT:
        Path(f"{boxes_file}.opt").write_text(f'SystemCall "touch {marker}";\n')
    comm.barrier()
    load_mesh(boxes_file, ["lower", "upper"], comm)
    assert not marker.exists()


@pytest.mark.parametrize("kind, said", [("fifo", "a FIFO, not a regular file"),
                                        ("device", "a device, not a regular file"),
                                        ("directory", "a directory, not a file")])
def test_not_a_regular_file(shared_dir, kind, said):
    path = shared_dir / f"{kind}.msh"
    if ROOT:
        {"fifo": lambda: os.mkfifo(path), "device": lambda: path.symlink_to("/dev/zero"),
         "directory": path.mkdir}[kind]()
    comm.barrier()
    expect_error(path, ["a"], rf"{kind}\.msh': is {said}")


@pytest.mark.parametrize("binary", [False, True])
def test_absurd_node_count(boxes_file, binary):
    """A declared node count that the file cannot hold is refused before gmsh allocates it."""
    path = boxes_file.parent / f"huge_{binary}.msh"

    def make():
        if binary:
            with gmsh_session():
                build_boxes("tet", 1)
                gmsh.option.setNumber("Mesh.Binary", 1)
                write(path)
            data = bytearray(path.read_bytes())
            at = data.index(b"\n$Nodes\n") + 8  # numEntityBlocks numNodes min max (size_t)
            data[at + 8:at + 16] = np.array([10**12], "<u8").tobytes()
        else:
            data = re.sub(rb"\$Nodes\n(\d+) \d+", rb"$Nodes\n\1 1000000000000",
                          boxes_file.read_bytes(), count=1)
        path.write_bytes(bytes(data))

    on_root(make)
    expect_error(path, ["lower"], r"huge_.*declares 1000000000000 nodes")


@pytest.mark.parametrize("moved, said", [((np.nan, 0.5, 0.0), "non-finite node coordinates"),
                                         ((1.0, 1.0, 0.0), "zero or negative measure"),
                                         ((1.2, 1.3, 0.0), "zero or negative measure")])
def test_degenerate_body(shared_dir, moved, said):
    """2x2 quadrilaterals whose centre node is moved: to NaN, onto a corner (a cell of zero
    area), out past a corner (tangled cells)."""
    path = shared_dir / "quads.msh"

    def make():
        with gmsh_session():
            gmsh.model.add("quads")
            s = gmsh.model.occ.addRectangle(0, 0, 0, 1, 1)
            gmsh.model.occ.synchronize()
            for _, c in gmsh.model.getEntities(1):
                gmsh.model.mesh.setTransfiniteCurve(c, 3)
            gmsh.model.mesh.setTransfiniteSurface(s)
            gmsh.model.mesh.setRecombine(2, s)
            gmsh.model.mesh.generate(2)
            tag = gmsh.model.addPhysicalGroup(2, [s])
            gmsh.model.setPhysicalName(2, tag, "plate")
            tags, x, _ = gmsh.model.mesh.getNodes()
            centre = int(np.argmin(np.linalg.norm(np.reshape(x, (-1, 3)) - (0.5, 0.5, 0), axis=1)))
            gmsh.model.mesh.setNode(int(tags[centre]), list(moved), [])
            write(path)

    on_root(make)
    expect_error(path, ["plate"], rf"quads\.msh.*body 'plate' has .*{said}")


def test_group_touches_and_interior_facets(boxes_file):
    ms = load_mesh(boxes_file, ["lower", "upper"], comm)
    assert ms.group_bodies["left"] == () and ms.group_touches["left"] == ("lower", "upper")
    assert ms.bodies["lower"].interior_facets("bottom") == 0
    assert ms.bodies["upper"].interior_facets("interface") == 0  # a boundary of each body


def test_no_named_groups(shared_dir):
    path = shared_dir / "unnamed.msh"

    def make():
        with gmsh_session():
            gmsh.model.add("unnamed")
            s = gmsh.model.occ.addRectangle(0, 0, 0, 1, 1)
            gmsh.model.occ.synchronize()
            gmsh.model.addPhysicalGroup(2, [s])  # no name
            gmsh.model.mesh.generate(2)
            write(path)

    on_root(make)
    expect_error(path, ["a"], r"unnamed\.msh.*no named physical groups")


@pytest.fixture
def boxes_file(shared_dir):
    path = shared_dir / "boxes.msh"

    def make():
        with gmsh_session():
            build_boxes("tet", 1)
            write(path)

    on_root(make)
    return path


def test_unknown_body(boxes_file):
    expect_error(boxes_file, ["lower", "ghost"],
                 r"boxes\.msh.*body 'ghost' is not a physical group.*available: .*lower.*upper")


def test_body_wrong_dimension(boxes_file):
    expect_error(boxes_file, ["lower", "interface"], r"boxes\.msh.*'interface' has dimension 2")


def test_empty_group():
    """A named volume group in a model meshed only up to dimension 2."""
    def make():
        gmsh.model.add("empty")
        v = gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        group(3, [v], "solid")
        gmsh.model.mesh.generate(2)

    with contextlib.ExitStack() as stack:
        if ROOT:
            stack.enter_context(gmsh_session())
        on_root(make)
        expect_error(gmsh, ["solid"], r"'solid' is empty")


def test_mixed_cell_types(shared_dir):
    path = shared_dir / "mixed.msh"

    def make():
        with gmsh_session():
            gmsh.model.add("mixed")
            a = gmsh.model.occ.addRectangle(0, 0, 0, 1, 1)
            b = gmsh.model.occ.addRectangle(1, 0, 0, 1, 1)
            gmsh.model.occ.fragment([(2, a)], [(2, b)])
            gmsh.model.occ.synchronize()
            group(2, [a, b], "both")
            gmsh.model.mesh.setRecombine(2, a)
            gmsh.model.mesh.generate(2)
            write(path)

    on_root(make)
    expect_error(path, ["both"], r"mixed\.msh.*'both' has mixed cell types")


def test_quad8_rejected(shared_dir):
    path = shared_dir / "quad8.msh"

    def make():
        with gmsh_session():
            build_2d("quad", 2, incomplete=True)
            write(path)

    on_root(make)
    expect_error(path, ["plate", "disk"], r"quad8\.msh.*'plate' has unsupported element type.*8")


def test_prisms_rejected(shared_dir):
    path = shared_dir / "prism.msh"

    def make():
        with gmsh_session():
            gmsh.model.add("prism")
            s = gmsh.model.occ.addRectangle(0, 0, 0, 1, 1)
            out = gmsh.model.occ.extrude([(2, s)], 0, 0, 1, numElements=[2], recombine=True)
            gmsh.model.occ.synchronize()
            group(3, [t for d, t in out if d == 3], "slab")
            gmsh.model.mesh.generate(3)
            write(path)

    on_root(make)
    expect_error(path, ["slab"], r"prism\.msh.*'slab' has unsupported element type.*Prism")


def test_2d_not_planar(shared_dir):
    path = shared_dir / "tilted.msh"

    def make():
        with gmsh_session():
            gmsh.model.add("tilted")
            s = gmsh.model.occ.addRectangle(0, 0, 0, 1, 1)
            gmsh.model.occ.rotate([(2, s)], 0, 0, 0, 1, 0, 0, 0.3)
            gmsh.model.occ.synchronize()
            group(2, [s], "sheet")
            gmsh.model.mesh.generate(2)
            write(path)

    on_root(make)
    expect_error(path, ["sheet"], r"tilted\.msh.*z coordinates are not constant")


# --------------------------------------------------------------------------
# mesh cache: a file read once is read again without gmsh
# --------------------------------------------------------------------------
def mesh_digest(ms: MeshSet) -> dict:
    """Global sums of coordinates and group sizes of every body (equal for equal meshes)."""
    out = {}
    for name, body in ms.bodies.items():
        imap = body.mesh.topology.index_map(0)
        x = body.mesh.geometry.x[: imap.size_local]
        out[name] = (comm.allreduce(float(np.sum(x * np.arange(1, 4))), op=MPI.SUM),
                     {g: comm.allreduce(len(idx), op=MPI.SUM)
                      for g, (_, idx) in body.groups.items()})
    return out


_READ_TWICE = """
import json, sys
from dolfinx_friction.io.gmsh import load_mesh
ms = load_mesh(sys.argv[1], ["lower", "upper"])
print(json.dumps({"gmsh": "gmsh" in sys.modules, "groups": ms.group_bodies,
                  "x": {n: b.mesh.geometry.x.tolist() for n, b in ms.bodies.items()},
                  "cells": {n: b.groups[n][1].size for n, b in ms.bodies.items()}}))
"""


@pytest.mark.skipif(comm.size > 1, reason="runs its own serial processes")
def test_cache_second_read_without_gmsh(boxes_file, tmp_path):
    import json
    import subprocess
    import sys
    env = dict(os.environ, DOLFINX_FRICTION_CACHE=str(tmp_path),
               PYTHONPATH=os.pathsep.join([str(Path(__file__).resolve().parents[2]),
                                           os.environ.get("PYTHONPATH", "")]))
    runs = [json.loads(subprocess.run([sys.executable, "-c", _READ_TWICE, str(boxes_file)],
                                      env=env, capture_output=True, text=True, check=True)
                       .stdout) for _ in range(2)]
    assert runs[0]["gmsh"]
    if not compat.NEW_API:  # 0.9 builds the coordinate element with gmshio, which imports gmsh
        assert not runs[1]["gmsh"]
    assert runs[0]["x"] == runs[1]["x"] and runs[0]["groups"] == runs[1]["groups"]
    assert runs[0]["cells"] == runs[1]["cells"]
    assert len(list((tmp_path / "meshes").glob("*.npz"))) == 1


def test_cache_damaged_entry_or_changed_file(shared_dir, monkeypatch):
    cache = Path(comm.bcast(tempfile.mkdtemp(prefix="mesh_cache_") if ROOT else None, root=0))
    monkeypatch.setenv("DOLFINX_FRICTION_CACHE", str(cache))
    path = shared_dir / "boxes.msh"

    def make():
        with gmsh_session():
            build_boxes("hex", 1)
            write(path)

    on_root(make)
    reference = mesh_digest(load_mesh(str(path), ["lower", "upper"], comm))
    entries = sorted((cache / "meshes").glob("*.npz")) if ROOT else []
    if ROOT:
        assert len(entries) == 1
        entries[0].write_bytes(b"not an npz")  # damaged: read with gmsh again, rewritten
    comm.barrier()
    assert mesh_digest(load_mesh(str(path), ["lower", "upper"], comm)) == reference
    assert mesh_digest(load_mesh(str(path), ["lower", "upper"], comm)) == reference
    if ROOT:
        assert entries[0].read_bytes()[:2] == b"PK"
        assert load_mesh(str(path), ["upper"], MPI.COMM_SELF).bodies.keys() == {"upper"}
        assert len(list((cache / "meshes").glob("*.npz"))) == 2  # other bodies: own entry
        with gmsh_session():  # another mesh in the same file name: a miss
            build_boxes("tet", 1)
            write(path)
    comm.barrier()
    tets = load_mesh(str(path), ["lower", "upper"], comm)
    assert num_cells(tets.bodies["upper"]) > (N - 1) ** 3
    comm.barrier()
    if ROOT:
        shutil.rmtree(cache, ignore_errors=True)
