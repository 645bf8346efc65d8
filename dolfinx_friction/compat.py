"""The dolfinx calls whose signature differs between dolfinx 0.5 and 0.9.

Every function here branches on ``dolfinx.__version__``.  The 0.5 branch is
tested (Debian 12: python3-dolfinx 0.5.2); the 0.9 branch (Debian 13) is
written from the dolfinx 0.9 Python sources (``dolfinx/mesh.py``,
``dolfinx/io/utils.py``, ``dolfinx/io/gmshio.py``, ``dolfinx/graph.py``) and
mirrors what 0.9's own ``gmshio.model_to_mesh`` does.
"""
from __future__ import annotations

import numpy as np
import dolfinx
import dolfinx.mesh

#: (major, minor) of the installed dolfinx, e.g. ``(0, 5)``.
DOLFINX_VERSION: tuple[int, ...] = tuple(int(p) for p in dolfinx.__version__.split(".")[:2])
#: True for dolfinx >= 0.9 (the Debian 13 API); False for 0.5-0.8.
NEW_API: bool = DOLFINX_VERSION >= (0, 9)
if not NEW_API and DOLFINX_VERSION != (0, 5):  # pragma: no cover
    import warnings

    warnings.warn(f"dolfinx_friction is tested with dolfinx 0.5 and written for 0.9; "
                  f"dolfinx {dolfinx.__version__} is treated like 0.5")


def _gmshio():
    """dolfinx's gmsh helpers module (``dolfinx.io.gmshio``; ``dolfinx.io.gmsh`` from 0.10)."""
    try:
        import dolfinx.io.gmshio as mod
    except ImportError:  # pragma: no cover - dolfinx >= 0.10
        import dolfinx.io.gmsh as mod  # type: ignore[no-redef]
    return mod


def ufl_mesh(gmsh_cell: int, gdim: int):
    """The ufl coordinate domain (equispaced Lagrange) for a Gmsh element type number."""
    if NEW_API:
        # 0.9: ufl_mesh(gmsh_cell, gdim, dtype) builds a basix.ufl element.
        return _gmshio().ufl_mesh(gmsh_cell, gdim, dtype=dolfinx.default_real_type)
    return _gmshio().ufl_mesh(gmsh_cell, gdim)


def cell_perm_gmsh(cell_type: dolfinx.mesh.CellType, num_nodes: int) -> np.ndarray:
    """Permutation ``p`` with ``nodes_dolfinx[i] = nodes_gmsh[p[i]]`` (``cpp.io.perm_gmsh``)."""
    # Same call in 0.5 and 0.9 (gmshio.cell_perm_array); kept here because the
    # module moved to dolfinx.io.gmsh in 0.10.
    return np.asarray(_gmshio().cell_perm_array(cell_type, num_nodes), dtype=np.int64)


def create_mesh(comm, cells: np.ndarray, x: np.ndarray, domain) -> dolfinx.mesh.Mesh:
    """``dolfinx.mesh.create_mesh`` with ``GhostMode.none`` (no ghost cells).

    ``cells``: (num_cells, nodes per cell) int64 in dolfinx node order, indices
    into the rows of ``x`` counted over all ranks in rank order; ``x``:
    (num_nodes, gdim).
    """
    cells = np.ascontiguousarray(cells, dtype=np.int64)
    x = np.ascontiguousarray(x, dtype=np.float64)
    if NEW_API:
        # 0.9: create_mesh(comm, cells, x, e, partitioner=None); the ghost
        # mode is a property of the partitioner.
        partitioner = dolfinx.mesh.create_cell_partitioner(dolfinx.mesh.GhostMode.none)
        return dolfinx.mesh.create_mesh(comm, cells, x, domain, partitioner)
    # 0.5: create_mesh(comm, cells, x, domain, ghost_mode, partitioner)
    return dolfinx.mesh.create_mesh(comm, cells, x, domain, ghost_mode=dolfinx.mesh.GhostMode.none)


def distribute_entity_data(mesh: dolfinx.mesh.Mesh, dim: int, entities: np.ndarray,
                           values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Send entities (rows of input node indices, dolfinx node order) to the ranks holding them.

    Returns (local entity-to-vertex array, values) for ``meshtags_from_entities``.
    """
    entities = np.ascontiguousarray(entities, dtype=np.int64)
    values = np.ascontiguousarray(values, dtype=np.int32)
    if NEW_API:
        # 0.9: dolfinx.io.utils.distribute_entity_data(mesh, dim, entities, values)
        # unpacks topology / geometry itself.
        from dolfinx.io.utils import distribute_entity_data as _ded
        return _ded(mesh, dim, entities, values)
    return dolfinx.cpp.io.distribute_entity_data(mesh._mesh, dim, entities, values)


def meshtags_from_entities(mesh: dolfinx.mesh.Mesh, dim: int, local_entities: np.ndarray,
                           values: np.ndarray):
    """MeshTags from entities given by local vertex indices (``distribute_entity_data`` output)."""
    local_entities = np.ascontiguousarray(local_entities, dtype=np.int32)
    values = np.ascontiguousarray(values, dtype=np.int32)
    if NEW_API:
        # 0.9 gmshio: adj = dolfinx.graph.adjacencylist(local_entities);
        # meshtags_from_entities(mesh, dim, adj, values)
        from dolfinx.graph import adjacencylist
        return dolfinx.mesh.meshtags_from_entities(mesh, dim, adjacencylist(local_entities), values)
    adj = dolfinx.cpp.graph.AdjacencyList_int32(local_entities)
    return dolfinx.mesh.meshtags_from_entities(mesh, dim, adj, values)


# --------------------------------------------------------------------- fem
def vector_space(mesh: dolfinx.mesh.Mesh, degree: int):
    """Vector Lagrange space of the given degree (one component per geometric axis)."""
    import dolfinx.fem
    gdim = mesh.geometry.dim
    if NEW_API:
        return dolfinx.fem.functionspace(mesh, ("Lagrange", degree, (gdim,)))
    return dolfinx.fem.VectorFunctionSpace(mesh, ("Lagrange", degree))


def space_degree(V) -> int:
    if NEW_API:
        return V.element.basix_element.degree
    return V.ufl_element().degree()


def geometry_degree(mesh: dolfinx.mesh.Mesh) -> int:
    if NEW_API:
        return mesh.geometry.cmap.degree
    return mesh.geometry.cmap.degree


def function(V):
    import dolfinx.fem
    return dolfinx.fem.Function(V)


def cell_dofs(V) -> np.ndarray:
    """Node (dof block) indices of every local cell, (num_cells, nodes per cell)."""
    dofs = V.dofmap.list
    if NEW_API:
        return np.asarray(dofs, dtype=np.int64)
    n = len(dofs.offsets) - 1
    return dofs.array.reshape(n, dofs.array.size // max(n, 1)).astype(np.int64)


def locate_nodes(V, dim: int, entities: np.ndarray) -> np.ndarray:
    """Local nodes (dof blocks) on mesh entities of any dimension."""
    import dolfinx.fem
    mesh = V.mesh
    mesh.topology.create_connectivity(dim, mesh.topology.dim)
    return np.asarray(dolfinx.fem.locate_dofs_topological(
        V, dim, np.asarray(entities, dtype=np.int32)), dtype=np.int64)


def scatter_reverse_add(f) -> None:
    """Add ghost values of a Function onto their owners."""
    import dolfinx.la
    mode = dolfinx.la.InsertMode.add if NEW_API else dolfinx.la.ScatterMode.add
    f.x.scatter_reverse(mode)


def scatter_forward(f) -> None:
    f.x.scatter_forward()


def form(expr):
    import dolfinx.fem
    return dolfinx.fem.form(expr)


def assemble_matrix(a):
    """Assembled PETSc matrix of a bilinear form (no boundary conditions)."""
    import dolfinx.fem.petsc
    A = dolfinx.fem.petsc.assemble_matrix(a)
    A.assemble()
    return A


def assemble_vector(L) -> np.ndarray:
    """Owned values of an assembled linear form, ghost contributions added to their owners."""
    import dolfinx.fem.petsc
    from petsc4py import PETSc
    b = dolfinx.fem.petsc.assemble_vector(L)
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    out = b.array.copy()
    b.destroy()
    return out


def scalar_space(mesh: dolfinx.mesh.Mesh, degree: int):
    import dolfinx.fem
    if NEW_API:
        return dolfinx.fem.functionspace(mesh, ("Lagrange", degree))
    return dolfinx.fem.FunctionSpace(mesh, ("Lagrange", degree))


# ------------------------------------------------------------------ output
def versions() -> dict[str, str]:
    """Versions of the libraries a result depends on."""
    import basix
    import ufl
    from petsc4py import PETSc
    import dolfinx_friction
    return {"dolfinx_friction": dolfinx_friction.__version__, "dolfinx": dolfinx.__version__,
            "basix": basix.__version__, "ufl": ufl.__version__,
            "petsc": ".".join(map(str, PETSc.Sys.getVersion())), "numpy": np.__version__}


def output_spaces(field) -> dict:
    """Spaces for XDMF output: XDMFFile wants functions of the mesh's geometry degree."""
    mesh = field.V.mesh
    g, k = geometry_degree(mesh), space_degree(field.V)
    scalar = scalar_space(mesh, k)
    return {"vector_in": field.V, "scalar_in": scalar,
            "vector_out": field.V if k == g else vector_space(mesh, g),
            "scalar_out": scalar if k == g else scalar_space(mesh, g)}


def _output_function(values: np.ndarray, space_in, space_out, name: str):
    import dolfinx.fem
    f = dolfinx.fem.Function(space_in)
    n = values.size
    f.x.array[:n] = values.ravel()
    f.x.scatter_forward()
    if space_out is not space_in:
        g = dolfinx.fem.Function(space_out)
        g.interpolate(f)
        f = g
    f.name = name
    return f


def write_fields(path, field, spaces: dict, nodal: dict[str, np.ndarray], t: float) -> None:
    """Displacement and nodal contact values (owned nodes) of a body into one XDMF file."""
    from dolfinx.io import XDMFFile
    mesh = field.V.mesh
    owned = field.n_owned
    with XDMFFile(mesh.comm, str(path), "w") as xdmf:
        xdmf.write_mesh(mesh)
        gd = field.gdim
        u = field.u.x.array[: owned * gd]
        xdmf.write_function(_output_function(u, spaces["vector_in"], spaces["vector_out"],
                                             "displacement"), t)
        for name, values in nodal.items():
            vector = values.shape[1] > 1
            f = _output_function(values[:owned], spaces["vector_in" if vector else "scalar_in"],
                                 spaces["vector_out" if vector else "scalar_out"], name)
            xdmf.write_function(f, t)
