"""The dolfinx calls whose signature differs between dolfinx 0.5, 0.9 and 0.11.

Every dolfinx / ufl / basix call whose spelling differs between the supported releases
lives here, and nothing else in the package (or its tests) branches on versions:

* Debian 12 (bookworm): dolfinx 0.5.2, Python 3.11, numpy 1.24, PETSc 3.18, Open MPI 4.1;
* Debian 13 (trixie): dolfinx 0.9.0, Python 3.13, numpy 2.2, PETSc 3.22, Open MPI 5.0;
* Debian sid: dolfinx 0.11.0, Python 3.14, numpy 2.4, PETSc 3.25, Open MPI 5.0.

Every branch is tested: the 0.5 one natively, the others by ``.ci/chroot.sh trixie|sid``
(the suite in a root filesystem of that suite), which also checks that a verification
scene gives the same reactions as on 0.5 within 1e-6 relative.  The 0.9+ branches mirror
what dolfinx's own ``model_to_mesh`` does.  The MPI launcher helpers at the end switch on
the Open MPI version (``mpirun -q`` is gone in Open MPI 5).
"""
from __future__ import annotations

import platform
import re

import numpy as np
import dolfinx
import dolfinx.mesh

#: (major, minor) of the installed dolfinx, e.g. ``(0, 5)``.
DOLFINX_VERSION: tuple[int, ...] = tuple(int(p) for p in dolfinx.__version__.split(".")[:2])
#: True for dolfinx >= 0.9 (the Debian 13 API); False for 0.5-0.8.
NEW_API: bool = DOLFINX_VERSION >= (0, 9)
#: True for dolfinx >= 0.10: ``create_mesh(comm, cells, e, x, ...)``, ``dolfinx.io.gmsh``,
#: ``fem.petsc.create_vector`` from a space.
API_0_10: bool = DOLFINX_VERSION >= (0, 10)
#: True for dolfinx >= 0.11: mixed-topology geometry (``cmaps[0]``, ``dofmaps[0]``).
API_0_11: bool = DOLFINX_VERSION >= (0, 11)
if not NEW_API and DOLFINX_VERSION != (0, 5):  # pragma: no cover
    import warnings

    warnings.warn(f"dolfinx_friction is tested with dolfinx 0.5 and written for 0.9; "
                  f"dolfinx {dolfinx.__version__} is treated like 0.5")


def ksp_pc_failed() -> int:
    """KSP's reason for a preconditioner (factorisation) that failed: ``DIVERGED_PC_FAILED``
    (PETSc 3.22), ``DIVERGED_PCSETUP_FAILED`` in PETSc 3.18; -11 in both."""
    from petsc4py import PETSc
    reasons = PETSc.KSP.ConvergedReason
    return getattr(reasons, "DIVERGED_PC_FAILED", None) or reasons.DIVERGED_PCSETUP_FAILED


def _gmshio():
    """dolfinx's gmsh helpers module (``dolfinx.io.gmshio``; ``dolfinx.io.gmsh`` from 0.10)."""
    try:
        import dolfinx.io.gmshio as mod
    except ImportError:  # pragma: no cover - dolfinx >= 0.10
        import dolfinx.io.gmsh as mod  # type: ignore[no-redef]
    return mod


# Gmsh element type -> (cell, degree) of the body cells that gmsh_io accepts
_GMSH_CELLS = {2: ("triangle", 1), 9: ("triangle", 2), 3: ("quadrilateral", 1),
               10: ("quadrilateral", 2), 4: ("tetrahedron", 1), 11: ("tetrahedron", 2),
               5: ("hexahedron", 1), 12: ("hexahedron", 2)}


def ufl_mesh(gmsh_cell: int, gdim: int):
    """The ufl coordinate domain (equispaced Lagrange) for a Gmsh element type number.

    0.5: built here as ``gmshio.ufl_mesh`` builds it (that module imports gmsh, ~0.5 s,
    and its table of cells exists only when gmsh imports); 0.9: ``gmshio.ufl_mesh``.
    """
    if NEW_API:
        # 0.9: ufl_mesh(gmsh_cell, gdim, dtype) builds a basix.ufl element.
        return _gmshio().ufl_mesh(gmsh_cell, gdim, dtype=dolfinx.default_real_type)
    import ufl
    shape, degree = _GMSH_CELLS[gmsh_cell]
    cell = ufl.Cell(shape, geometric_dimension=gdim)
    return ufl.Mesh(ufl.VectorElement(ufl.FiniteElement("Lagrange", cell, degree,
                                                        variant="equispaced")))


def model_to_mesh(model, comm, rank: int, gdim: int) -> tuple:
    """``(mesh, cell_tags, facet_tags)`` of the gmsh model on ``rank`` (dolfinx's
    ``model_to_mesh``: a tuple up to 0.9, a named tuple of six fields from 0.10)."""
    data = _gmshio().model_to_mesh(model, comm, rank, gdim=gdim)
    if API_0_10:
        return data.mesh, data.cell_tags, data.facet_tags
    return data


def cell_perm_gmsh(cell_type: dolfinx.mesh.CellType, num_nodes: int) -> np.ndarray:
    """Permutation ``p`` with ``nodes_dolfinx[i] = nodes_gmsh[p[i]]`` (``cpp.io.perm_gmsh``)."""
    if NEW_API:  # gmshio.cell_perm_array; the module moved to dolfinx.io.gmsh in 0.10
        return np.asarray(_gmshio().cell_perm_array(cell_type, num_nodes), dtype=np.int64)
    import dolfinx.cpp.io  # 0.5: what gmshio.cell_perm_array calls, without importing gmsh
    return np.asarray(dolfinx.cpp.io.perm_gmsh(cell_type, num_nodes), dtype=np.int64)


def create_mesh(comm, cells: np.ndarray, x: np.ndarray, domain) -> dolfinx.mesh.Mesh:
    """``dolfinx.mesh.create_mesh`` with ``GhostMode.none`` (no ghost cells).

    ``cells``: (num_cells, nodes per cell) int64 in dolfinx node order, indices
    into the rows of ``x`` counted over all ranks in rank order; ``x``:
    (num_nodes, gdim).
    """
    cells = np.ascontiguousarray(cells, dtype=np.int64)
    x = np.ascontiguousarray(x, dtype=np.float64)
    if API_0_10:  # create_mesh(comm, cells, e, x, partitioner=None, max_facet_to_cell_links=2)
        return dolfinx.mesh.create_mesh(comm, cells, domain, x, _ghostless_partitioner())
    if NEW_API:
        # 0.9: create_mesh(comm, cells, x, e, partitioner=None); the ghost
        # mode is a property of the partitioner.
        return dolfinx.mesh.create_mesh(comm, cells, x, domain, _ghostless_partitioner())
    # 0.5: create_mesh(comm, cells, x, domain, ghost_mode, partitioner); cells as an
    # AdjacencyList (a bare array is first tried against it, and the TypeError's message
    # formats both arrays)
    cells = dolfinx.cpp.graph.AdjacencyList_int64(cells)
    return dolfinx.mesh.create_mesh(comm, cells, x, domain, ghost_mode=dolfinx.mesh.GhostMode.none)


def _ghostless_partitioner():
    """The cell partitioner without ghost cells (0.9, 0.10); from 0.11 it also takes the
    most cells a facet joins, 2 (a non-branching mesh)."""
    if DOLFINX_VERSION >= (0, 11):
        return dolfinx.mesh.create_cell_partitioner(dolfinx.mesh.GhostMode.none, 2)
    return dolfinx.mesh.create_cell_partitioner(dolfinx.mesh.GhostMode.none)


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


def coordinate_element(mesh: dolfinx.mesh.Mesh):
    """The mesh's coordinate element (``geometry.cmap``; ``geometry.cmaps[0]`` from 0.11)."""
    return mesh.geometry.cmaps[0] if API_0_11 else mesh.geometry.cmap


def geometry_degree(mesh: dolfinx.mesh.Mesh) -> int:
    return coordinate_element(mesh).degree


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


def _host_tag() -> str:
    """A short hash of this CPU's model and instruction-set flags (``/proc/cpuinfo``; the
    machine's architecture where that is unreadable)."""
    import hashlib
    try:
        with open("/proc/cpuinfo") as f:
            lines = [ln for ln in f if ln.split(":")[0].strip() in ("model name", "flags",
                                                                   "Features", "CPU part")]
    except OSError:
        lines = []
    text = "".join(dict.fromkeys(lines)) or platform.machine()
    return hashlib.sha1(text.encode()).hexdigest()[:12]


#: C compiler flags added to dolfinx's for every form's kernel: math functions need not set
#: ``errno``, so the compiler computes repeated ``pow(J, -2/3)``-like calls of a
#: finite-strain tangent once (the Neo-Hookean Jacobian on hexahedra assembles in 0.6x the
#: time); the kernel uses this CPU's vector instructions but no fused multiply-add (which
#: rounds differently): the Neo-Hookean Jacobian of the full ironing of
#: benchmarks/bench_ccx_nlgeom.py assembles in 17-18 instead of 23-24 ms, its values the
#: same bit for bit as with ``-O2`` alone.  The host's tag is a macro of no use but in the
#: flags, on which dolfinx's kernel cache is keyed: a cache shared by machines of other
#: CPUs never loads a foreign kernel.  Only on x86-64 (where GCC and Clang both take
#: ``-march=native``).
PURE_MATH_FLAGS = ["-fno-math-errno"] + (
    ["-march=native", "-ffp-contract=off", f"-DDOLFINX_FRICTION_HOST={_host_tag()}"]
    if platform.machine() in ("x86_64", "AMD64") else [])


def form(expr):
    """A compiled form, its kernel built with :data:`PURE_MATH_FLAGS` added."""
    import dolfinx.fem
    import dolfinx.jit
    if NEW_API:  # 0.9+: jit_options, get_options
        args = dolfinx.jit.get_options()["cffi_extra_compile_args"]
        return dolfinx.fem.form(expr, jit_options={
            "cffi_extra_compile_args": [*args, *PURE_MATH_FLAGS]})
    args = dolfinx.jit.get_parameters()["cffi_extra_compile_args"]
    return dolfinx.fem.form(expr, jit_params={
        "cffi_extra_compile_args": [*args, *PURE_MATH_FLAGS]})


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


def petsc_vector(u):
    """The PETSc Vec (ghosted) behind a dolfinx Function."""
    return u.x.petsc_vec if NEW_API else u.vector


def create_vector(L):
    """A ghosted PETSc vector for a compiled linear form (0.10+ builds it from the form's
    test space)."""
    import dolfinx.fem.petsc
    return dolfinx.fem.petsc.create_vector(L.function_spaces[0] if API_0_10 else L)


def create_matrix(a, blocked: bool = False):
    """An empty PETSc matrix with the sparsity of a compiled bilinear form, or (0.10+) of a
    2-D list of them in dolfinx's block numbering; ``blocked``: of type ``baij`` (the
    second argument is ``mat_type`` in 0.5, ``kind`` in 0.9+)."""
    import dolfinx.fem.petsc
    return dolfinx.fem.petsc.create_matrix(a, "baij" if blocked else None)


def assemble_matrix_into(A, a, bcs=()) -> None:
    """Add a compiled bilinear form into ``A`` (dolfinx's treatment of ``bcs``: their rows
    and columns zero, 1 on the diagonal), then assemble ``A``."""
    import dolfinx.fem.petsc
    dolfinx.fem.petsc.assemble_matrix(A, a, list(bcs))
    A.assemble()


def snes_problem(problem):
    """The parts of a dolfinx 0.10+ ``fem.petsc.NonlinearProblem`` the contact joins:
    ``snes`` (its SNES), ``J`` (its compiled Jacobian form, or 2-D list of them) and
    ``spaces`` (of its unknowns, in block order).  Raises ContactSetupError for an older
    dolfinx, another object, a nest matrix or a preconditioner form."""
    from types import SimpleNamespace
    from dolfinx_friction.errors import ContactSetupError
    if not API_0_10:
        raise ContactSetupError(f"add_contact needs dolfinx >= 0.10's SNES NonlinearProblem "
                                f"(this is dolfinx {dolfinx.__version__}): use BlockProblem "
                                f"with snes_solve or solve_steps")
    from dolfinx.fem.petsc import NonlinearProblem
    if not isinstance(problem, NonlinearProblem):
        raise ContactSetupError(f"add_contact: {type(problem).__name__} is not a "
                                f"dolfinx.fem.petsc.NonlinearProblem")
    if problem.A.getType() == "nest":
        raise ContactSetupError("add_contact: a nest matrix cannot hold the couplings between "
                                "bodies: make the NonlinearProblem with kind=\"mpi\"")
    if problem.P_mat is not None:
        raise ContactSetupError("add_contact: a preconditioner form P is not supported (the "
                                "contact tangent would miss it)")
    u = problem.u
    unknowns = list(u) if isinstance(u, (list, tuple)) else [u]
    return SimpleNamespace(snes=problem.solver, J=problem.J,
                           spaces=[w.function_space for w in unknowns])


def assign_to_vector(u, x) -> None:
    """Copy the Function(s) ``u`` into the (block) vector ``x`` (dolfinx 0.10+)."""
    import dolfinx.fem.petsc
    dolfinx.fem.petsc.assign(u, x)


def assign_from_vector(x, u) -> None:
    """Copy the (block) vector ``x`` into the Function(s) ``u``, ghosts included
    (dolfinx 0.10+)."""
    import dolfinx.fem.petsc
    dolfinx.fem.petsc.assign(x, u)
    for f in (u if isinstance(u, (list, tuple)) else [u]):
        f.x.scatter_forward()


def assemble_vector_into(b, L) -> None:
    """Add a compiled linear form into the ghosted vector ``b`` and sum the ghost
    contributions onto their owners."""
    import dolfinx.fem.petsc
    from petsc4py import PETSc
    dolfinx.fem.petsc.assemble_vector(b, L)
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)


def assemble_residual_into(b, L, a, bcs, x) -> None:
    """``b = L(x)`` (zeroed first), lifted and with ``b = x - g`` on the rows of ``bcs``:
    the residual of a Newton step ``x <- x - dx`` (what dolfinx's NonlinearProblem does)."""
    import dolfinx.fem.petsc
    from petsc4py import PETSc
    with b.localForm() as local:
        local.set(0.0)
    dolfinx.fem.petsc.assemble_vector(b, L)
    dolfinx.fem.petsc.apply_lifting(b, [a], [list(bcs)], [x], -1.0)
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    dolfinx.fem.petsc.set_bc(b, list(bcs), x, -1.0)


def set_bc_values(x, bcs) -> None:
    """Write the values of ``bcs`` into their rows of the (ghosted) vector ``x``."""
    import dolfinx.fem.petsc
    dolfinx.fem.petsc.set_bc(x, list(bcs))


def bc_local_dofs(bc, n_owned: int) -> np.ndarray:
    """Local (unrolled) dof indices of a DirichletBC that are among the ``n_owned`` owned
    dofs of its space."""
    dofs = np.asarray(bc.dof_indices()[0], dtype=np.int64)
    return dofs[dofs < n_owned]


def bc_on_space(bc, V) -> bool:
    """Whether a DirichletBC constrains dofs of ``V`` (or of a subspace of it)."""
    W = bc.function_space
    return V._cpp_object.contains(getattr(W, "_cpp_object", W))


def cell_function(expr, mesh, shape: tuple, name: str):
    """A DG0 Function (cell values, as XDMF cell data) named ``name`` and the compiled
    expression that fills it: ``expr`` (a UFL expression of value shape ``shape``, ``()``
    for a scalar) at the cell midpoints.  ``f.interpolate(expression)`` refreshes ``f``
    from the current values of the coefficients of ``expr``."""
    import basix
    import dolfinx.fem
    cell = getattr(basix.CellType, mesh.topology.cell_type.name)
    midpoint = np.asarray(basix.geometry(cell)).mean(axis=0)[None]
    if NEW_API:
        V = dolfinx.fem.functionspace(mesh, ("DG", 0, shape))
    elif len(shape) == 0:
        V = dolfinx.fem.FunctionSpace(mesh, ("DG", 0))
    elif len(shape) == 1:
        V = dolfinx.fem.VectorFunctionSpace(mesh, ("DG", 0), dim=shape[0])
    else:
        V = dolfinx.fem.TensorFunctionSpace(mesh, ("DG", 0), shape=shape)
    f = dolfinx.fem.Function(V)
    f.name = name
    return f, dolfinx.fem.Expression(expr, midpoint)


def quadrature_expression(expr, mesh, degree: int):
    """A compiled UFL expression at the points of a quadrature rule of ``degree`` on the
    mesh's cells."""
    import basix
    import dolfinx.fem
    cell = getattr(basix.CellType, mesh.topology.cell_type.name)
    points, _ = basix.make_quadrature(cell, degree)
    return dolfinx.fem.Expression(expr, points)


def evaluate_on_cells(expression, mesh, cells: np.ndarray) -> np.ndarray:
    """Values of a compiled expression on local cells, (cells, points * size)."""
    cells = np.asarray(cells, dtype=np.int32)
    if NEW_API:
        return np.asarray(expression.eval(mesh, cells))
    return np.asarray(expression.eval(cells))


def evaluate_on_owned_cells(expression, mesh) -> np.ndarray:
    """Values of a compiled expression on this rank's owned cells, (cells, points * size)."""
    cells = np.arange(mesh.topology.index_map(mesh.topology.dim).size_local, dtype=np.int32)
    return evaluate_on_cells(expression, mesh, cells)


def tagged(tags, value: int) -> np.ndarray:
    """Local entities of a MeshTags object that carry ``value``."""
    return np.asarray(tags.indices[tags.values == value], dtype=np.int32)


def tags_of(tags, mesh: dolfinx.mesh.Mesh) -> bool:
    """Whether the MeshTags ``tags`` were made on ``mesh`` (the same topology object: 0.9's
    ``tags.topology``, 0.5's ``tags.mesh.topology``; pybind11 and nanobind hand out one
    wrapper per C++ object)."""
    topology = tags.topology if NEW_API else tags.mesh.topology
    ours = getattr(mesh.topology, "_cpp_object", mesh.topology)  # 0.10+: a Python wrapper
    return getattr(topology, "_cpp_object", topology) is ours


def scalar_constant(mesh: dolfinx.mesh.Mesh, value: float):
    """A ``fem.Constant`` holding a real scalar (0.9 wants a numpy scalar of
    ``dolfinx.default_scalar_type``; 0.5 takes a Python float)."""
    import dolfinx.fem
    if NEW_API:
        return dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(value))
    return dolfinx.fem.Constant(mesh, value)


def geometry_dofmap(mesh: dolfinx.mesh.Mesh) -> np.ndarray:
    """Geometry node indices of every local cell, (num_cells, nodes per cell).

    0.9: ``mesh.geometry.dofmap`` is that 2D array (0.11: ``dofmaps[0]``); 0.5: an
    AdjacencyList.
    """
    dofmap = mesh.geometry.dofmaps[0] if API_0_11 else mesh.geometry.dofmap
    if NEW_API:
        return np.asarray(dofmap)
    n = len(dofmap.offsets) - 1
    return dofmap.array.reshape(n, dofmap.array.size // max(n, 1))


def scalar_space(mesh: dolfinx.mesh.Mesh, degree: int):
    import dolfinx.fem
    if NEW_API:
        return dolfinx.fem.functionspace(mesh, ("Lagrange", degree))
    return dolfinx.fem.FunctionSpace(mesh, ("Lagrange", degree))


# -------------------------------------------------------------------- plot
def vtk_mesh(V):
    """``(topology, cell_types, x)`` of a Lagrange space for VTK/pyvista, built on its dofs.

    0.5: ``dolfinx.plot.create_vtk_mesh(V)``; renamed ``vtk_mesh`` in 0.9.
    """
    import dolfinx.plot
    if NEW_API:
        return dolfinx.plot.vtk_mesh(V)
    return dolfinx.plot.create_vtk_mesh(V)


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


# ------------------------------------------------------------- MPI launcher
def open_mpi_major() -> int:
    """Major version of the Open MPI that mpi4py uses (4: Debian 12, 5: Debian 13); 0 if
    the MPI library is not Open MPI."""
    from mpi4py import MPI
    match = re.search(r"Open MPI v(\d+)", MPI.Get_library_version())
    return int(match.group(1)) if match else 0


def mpirun_command(n: int) -> list[str]:
    """``mpirun`` arguments that start ``n`` ranks on this machine (oversubscribed, not
    bound to cores), as quietly as the launcher allows; append the program to run.

    Open MPI 4 takes ``-q`` (no launcher messages when a rank exits non-zero); Open MPI 5
    (PRRTE) rejects it and cannot be silenced: filter its stderr with
    :func:`mpirun_stderr`.
    """
    quiet = ["-q"] if 0 < open_mpi_major() < 5 else []
    return ["mpirun", *quiet, "-n", str(n), "--oversubscribe", "--bind-to", "none"]


def mpirun_environment(env: dict[str, str]) -> dict[str, str]:
    """``env`` plus what :func:`mpirun_command` needs: running as root allowed, no
    cross-memory attach (often forbidden in containers); with Open MPI 5 also only the
    self and shared-memory transports (its TCP transport warns that it finds no
    reachable interface pairing inside a chroot).  Values already in ``env`` win."""
    out = dict(env)
    out.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    out.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    out.setdefault("OMPI_MCA_btl_vader_single_copy_mechanism", "none")
    if open_mpi_major() >= 5:
        out.setdefault("OMPI_MCA_btl_sm_single_copy_mechanism", "none")
        out.setdefault("OMPI_MCA_btl", "self,sm")
    return out


# Open MPI 5's own messages on stderr: framed notices ("prterun detected that one or
# more processes exited with non-zero status ...") and PMIx error lines.
_FRAME = re.compile(r"^-{20,}$")
_PMIX = re.compile(r"^\[[^\]]*\] PMIX ERROR: ")


def mpirun_stderr(text: str) -> str:
    """The stderr of an :func:`mpirun_command` job without the launcher's own messages
    (what Open MPI 4's ``-q`` suppresses); unchanged with Open MPI 4."""
    if not open_mpi_major() >= 5:
        return text
    kept, framed = [], False
    for line in text.splitlines(keepends=True):
        if _FRAME.match(line.rstrip("\n")):
            framed = not framed
            continue
        if not framed and not _PMIX.match(line):
            kept.append(line)
    return "".join(kept)
