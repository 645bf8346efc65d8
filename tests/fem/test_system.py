"""The assembled system: COO pattern, exact global Jacobian, surfaces, serial = parallel."""
from __future__ import annotations

import gc
import json
from dataclasses import replace

import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx_friction.scene.runner import run
from dolfinx_friction.fem.pattern import CooPattern
from dolfinx_friction.contact.shapes import face_areas
from dolfinx_friction.scene.model import (BC, Body, ContactPair, Load, Rigid, RigidMotion, Scene,
                                          SolverSettings, Step)
from dolfinx_friction.scene.build import ContactProblem
from dolfinx_friction.scene.driver import Solver
from dolfinx_friction.nls import LinearSolver
from dolfinx_friction.fem.surfaces import SlaveNodes, master_faces
from dolfinx_friction.reference import cases, meshes
from tests.finite_differences import scene_tangent_error


def _csr_rows(A: PETSc.Mat, N: int) -> np.ndarray:
    """The owned rows of ``A`` as a dense array (n_owned, N)."""
    start, end = A.getOwnershipRange()
    indptr, indices, data = A.getValuesCSR()
    rows = np.zeros((end - start, N))
    for i in range(end - start):
        rows[i, indices[indptr[i]:indptr[i + 1]]] = data[indptr[i]:indptr[i + 1]]
    return rows


@pytest.mark.parametrize("extended", [False, True])
def test_coo_pattern_sums_blocks_like_a_dense_matrix(comm, extended):
    """Two blocks in one pattern, or the second added to the first's pattern (extended)."""
    rng = np.random.default_rng(comm.rank)
    n_owned = 5 + comm.rank
    N = comm.allreduce(n_owned)
    blocks = [(rng.integers(0, N, 50), rng.integers(0, N, 50)) for _ in range(2)]
    values = [rng.standard_normal(50) for _ in range(2)]
    if extended:
        base = CooPattern(comm, n_owned, blocks[:1])
        pattern = base.extended(blocks[1:])
        data = pattern.gather_values(0, values[1])
        data[pattern.base_slots] += base.gather_values(0, values[0])
        assert pattern.nnz == CooPattern(comm, n_owned, blocks).nnz
    else:
        pattern = CooPattern(comm, n_owned, blocks)
        data = pattern.gather_values(0, values[0]) + pattern.gather_values(1, values[1])
    data[pattern.diagonal_slots] += 100.0  # every owned diagonal has its slot
    A = pattern.create_matrix()
    pattern.fill(A, data)
    dense = np.zeros((N, N))
    for (rows, cols), vals in zip(blocks, values):
        np.add.at(dense, (rows, cols), vals)
    dense = comm.allreduce(dense) + 100.0 * np.eye(N)
    start, end = A.getOwnershipRange()
    assert np.abs(_csr_rows(A, N) - dense[start:end]).max() < 1e-13


def test_body_jacobian_values_sit_at_their_entries(comm):
    """A nonlinear body's Jacobian values (in serial copied from PETSc's block-AIJ array, in
    its order) at its entries make the matrix ``getValuesCSR`` reads."""
    import dolfinx.mesh
    import ufl
    from dolfinx_friction import _compat as compat
    from dolfinx_friction.fem.body_forms import BodyForms
    V = compat.vector_space(dolfinx.mesh.create_unit_square(comm, 4, 3), 1)
    u = compat.function(V)
    u.interpolate(lambda x: np.vstack([0.1 * x[0] * x[1], 0.05 * x[0] ** 2]))
    F = ufl.Identity(2) + ufl.grad(u)
    E = (F.T * F - ufl.Identity(2)) / 2
    body = BodyForms(ufl.derivative((ufl.tr(E) ** 2 + ufl.inner(E, E)) * ufl.dx, u,
                                    ufl.TestFunction(V)), u, None, [])
    assert not body.linear
    body.assemble_jacobian()
    rows, cols = body.jacobian_entries()  # (the storage order is checked on these values)
    N = body.A.getSize()[1]
    for shift in (0.0, 0.2):  # and read again at another u, as Newton does
        u.interpolate(lambda x: np.vstack([0.1 * x[0] * x[1] + shift * x[1] ** 2,
                                           0.05 * x[0] ** 2 - shift * x[0] * x[1]]))
        body.assemble_jacobian()
        dense = np.zeros((body.A.getLocalSize()[0], N))
        np.add.at(dense, (rows, cols), body.jacobian_values())
        assert np.array_equal(dense, _csr_rows(body.A, N))


def test_fill_over_writes_a_block_over_a_kept_base(comm):
    """``fill_over``: the base with one block's sums at their slots (``gather_slots``), fill
    after fill with new block values; also after the matrix was changed in between (scaled:
    the whole base is written again) and after a plain ``fill``."""
    rng = np.random.default_rng(comm.rank)
    n_owned = 6 + comm.rank
    N = comm.allreduce(n_owned)
    blocks = [(rng.integers(0, N, 60), rng.integers(0, N, 60)) for _ in range(2)]
    pattern = CooPattern(comm, n_owned, blocks)
    base = pattern.gather_values(0, rng.standard_normal(60))
    base[pattern.diagonal_slots] += 10.0
    A = pattern.create_matrix()
    for change in (None, "scale", "fill", None):
        if change == "scale":
            A.scale(3.0)
        elif change == "fill":
            pattern.fill(A, np.zeros(pattern.nnz))
        values = rng.standard_normal(60)
        slots, sums = pattern.gather_slots(1, values)
        assert np.array_equal(slots, np.unique(slots))
        pattern.fill_over(A, base, slots, base[slots] + sums)
        expected = A.duplicate()
        pattern.fill(expected, base + pattern.gather_values(1, values))
        assert np.array_equal(_csr_rows(A, N), _csr_rows(expected, N))  # the same sums


def test_fill_layered_writes_blocks_over_a_base_and_adds_on_top():
    """``fill_layered`` (serial): the base, one block's values written over it at its
    distinct slots, another block's sums added on top; fill after fill, the same matrix as
    the values summed densely (the written block replaces the base where they meet)."""
    from mpi4py import MPI
    comm = MPI.COMM_SELF
    rng = np.random.default_rng(7)
    N = 8
    cells = np.array([(i, j) for i in range(N) for j in range(N) if abs(i - j) <= 2])
    over = cells[rng.permutation(len(cells))[:30]]  # distinct entries
    blocks = [(cells[:, 0], cells[:, 1]), (over[:, 0], over[:, 1]),
              (rng.integers(0, N, 40), rng.integers(0, N, 40))]
    pattern = CooPattern(comm, N, blocks)
    at = pattern.distinct_slots(1)
    assert at is not None
    A = pattern.create_matrix()
    for _ in range(2):
        base = pattern.gather_values(0, rng.standard_normal(len(cells)))
        written, added = rng.standard_normal(len(over)), rng.standard_normal(40)
        slots, sums = pattern.gather_slots(2, added)
        pattern.fill_layered(A, base, [(at, written)], slots, sums)
        B = A.duplicate()
        pattern.fill(B, base)
        expected = _csr_rows(B, N)
        expected[over[:, 0], over[:, 1]] = written
        np.add.at(expected, (blocks[2][0], blocks[2][1]), added)
        assert np.allclose(_csr_rows(A, N), expected, rtol=0, atol=1e-14)


def _boxes_scene(mesh, model: str = "linear", degree: int | None = None,
                 master: str = "foundation", **contact) -> Scene:
    """The block pressed on the foundation and slid; ``master = "plane"``: on a rigid plane
    where the foundation's top is (the foundation left out)."""
    # CalculiX's K and lambda: with the default lambda = E/h a slave node's trial force
    # lies within the finite-difference step of the Coulomb cone (1e-2 at h = 1e-7, 2e-9
    # at 1e-8): a kink, not a tangent error
    contact = {"K": "calculix", "stick_slope": "calculix", **contact}
    if master == "plane":
        return Scene(
            mesh=mesh, bodies=(Body("block", 1000.0, 0.3, model=model, degree=degree),),
            rigids=(Rigid("floor", "plane", point=(0.0, 0.0, 0.5), normal=(0.0, 0.0, 1.0)),),
            contacts=(ContactPair("block_bottom", "floor", **contact),),
            steps=(Step("press", bcs=(BC("block_top", (0.0, 0.0, -0.01)),)),
                   Step("slide", increments=3, bcs=(BC("block_top", (0.04, 0.01, -0.01)),))))
    return Scene(
        mesh=mesh, bodies=(Body("block", 1000.0, 0.3, model=model, degree=degree),
                           Body("foundation", 2000.0, 0.25, model=model, degree=degree)),
        contacts=(ContactPair("block_bottom", "foundation_top", **contact),),
        steps=(Step("press", bcs=(BC("foundation_bottom", (0.0, 0.0, 0.0)),
                                  BC("block_top", (0.0, 0.0, -0.01)))),
               Step("slide", increments=3, bcs=(BC("block_top", (0.04, 0.01, -0.01)),))))


@pytest.mark.parametrize("mu, model, degree, cells, master", [
    (0.0, "linear", None, "hex", "foundation"), (0.3, "linear", None, "hex", "foundation"),
    (0.3, "neo-hookean", None, "hex", "foundation"),
    (0.3, "saint-venant-kirchhoff", None, "hex", "foundation"),
    (0.3, "neo-hookean", 2, "hex", "foundation"), (0.3, "neo-hookean", 2, "tet", "foundation"),
    (0.3, "neo-hookean", 2, "hex", "plane"), (0.3, "neo-hookean", 2, "tet", "plane"),
    (0.0, "linear", 2, "tet", "plane")])
def test_global_jacobian_matches_finite_differences(shared_dir, mu, model, degree, cells,
                                                    master):
    """The assembled Jacobian (bulk + contact, pairing frozen) is the derivative of the
    residual, through the system's public calls; also with finite-strain bodies, and with
    quadratic slave faces (Q9, T6), which on a rigid plane spread each slave node's force
    over the faces around it (across ranks under MPI)."""
    mesh = meshes.two_boxes(shared_dir / "boxes.msh", tets=cells == "tet")
    problem = ContactProblem(_boxes_scene(mesh, model, degree, master, mu=mu))
    Solver(problem).run()
    error = scene_tangent_error(problem)
    print(f"\n{model}, {cells} P{degree or 1} on the {master}, mu = {mu}: FD rel error "
          f"{error:.1e}")
    assert error < 1e-8, error


def test_rigid_body_modes_span_the_kernel_of_the_bulk_stiffness(shared_dir):
    """The near null space given to multigrid: orthonormal, and each body's stiffness maps
    its part of each mode to round-off."""
    from dolfinx_friction import _compat as compat
    from dolfinx_friction.scene.build import elastic_forms
    mesh = meshes.two_boxes(shared_dir / "boxes.msh")
    problem = ContactProblem(_boxes_scene(mesh))
    modes = problem.rigid_body_modes().getVecs()
    assert len(modes) == 6
    gram = np.array([[a.dot(b) for b in modes] for a in modes])
    np.testing.assert_allclose(gram, np.eye(6), atol=1e-14)  # measured 2.2e-16
    for k, field in enumerate(problem.fields):
        K = compat.assemble_matrix(compat.form(elastic_forms(field)[1]))
        part, Kpart = K.createVecRight(), K.createVecLeft()
        for m in modes:
            part.setArray(m.getArray(readonly=True)[problem.system.block_slice(k)])
            K.mult(part, Kpart)
            assert Kpart.norm() < 1e-14 * K.norm(PETSc.NormType.INFINITY), Kpart.norm()


def test_iterative_solver_gives_the_direct_answer(shared_dir):
    """GMRES + GAMG (near null space and block size from the solver) reaches the reactions of
    the default MUMPS run, also when asked to keep a factorisation (there is none to keep:
    the request is ignored); the next run in the process has the default solver again."""
    mesh = meshes.two_boxes(shared_dir / "boxes.msh")
    scene = _boxes_scene(mesh, mu=0.3)
    direct = run(scene, write=False).increments
    options = {"ksp_type": "gmres", "pc_type": "gamg", "ksp_rtol": 1e-12, "ksp_max_it": 500}
    for reuse in (None, True):
        gamg, solver = _solve(scene, petsc_options=options, reuse_factorisation=reuse)
        assert solver.linear.settings()["pc_type"] == "gamg"
        del solver
        for a, b in zip(gamg, direct):
            R = np.abs(b.reactions["block_top"]).max()  # Newton tolerance; measured 5e-16
            np.testing.assert_allclose(a.reactions["block_top"], b.reactions["block_top"],
                                       atol=1e-9 * R)
        assert [i.iterations for i in gamg] == [i.iterations for i in direct]
    # options given to a run are not left to the next one in the process: they go with their
    # solver (a solver in a reference cycle goes at the collector's next pass, which comes at
    # different times on different ranks)
    gc.collect()
    assert not [k for k in PETSc.Options().getAll() if k.startswith("dolfinx_friction_")]
    _, solver = _solve(scene)
    assert solver.linear.settings()["pc_type"] == "lu"


def test_solver_table_chooses_the_linear_solver(shared_dir):
    """A scene's ``[solver]``: "iterative" (GMRES + GAMG at the relative residual Newton
    asks) reaches the reactions of the direct solve within Newton's tolerance, in as many
    Newton iterations; "auto" factorises this small system unless ``direct_max_dofs`` is
    below its size; summary.json records the request, the size and what ran.  The same on
    every rank count."""
    mesh = meshes.two_boxes(shared_dir / "boxes.msh")
    scene = _boxes_scene(mesh, mu=0.3)
    direct = run(scene, write=False)
    for settings in (SolverSettings("iterative"), SolverSettings(direct_max_dofs=10)):
        out = shared_dir / "solver_table" / settings.linear
        result = run(replace(scene, solver=settings), out=out)
        for a, b in zip(result.increments, direct.increments):
            # two iterates within Newton's residual tolerance (1e-9 of the forces): measured
            # 5.4e-8 R apart serially, 2.8e-8 R on 2 ranks
            R = np.abs(b.reactions["block_top"]).max()
            np.testing.assert_allclose(a.reactions["block_top"], b.reactions["block_top"],
                                       atol=2e-7 * R)
        assert [i.iterations for i in result.increments] == \
            [i.iterations for i in direct.increments]
        summary = json.loads((out / "summary.json").read_text())["resolved"]
        assert summary["solver"]["chosen"] == "iterative"
        assert summary["solver"]["dofs"] == direct.problem.system.x.getSize()
        assert summary["linear_solver"]["pc_type"] == "gamg"
    summary = json.loads((shared_dir / "solver_table" / "auto" / "summary.json").read_text())[
        "resolved"]
    assert summary["solver"]["direct_max_dofs"] == 10


def _solve(scene, comm=MPI.COMM_WORLD, **kwargs):
    """(reactions per increment, the Solver) of a run."""
    solver = Solver(ContactProblem(scene, comm), **kwargs)
    increments = []
    solver.run(increments.append)
    return increments, solver


@pytest.mark.parametrize("mu", [0.0, 0.3])
def test_condensed_solve_gives_the_direct_answer(shared_dir, mu):
    """Linear bodies: the bulk factorisation kept for the run with the contact condensed
    (linear.Condensed) reaches the reactions of a factorisation per iteration to round-off,
    in the same Newton iterations, on every rank count (under MPI: distributed MUMPS, the
    dense part on every rank), and the serial run's reactions.  A deep foundation: the
    contact surface is small against the bulk, where it pays."""
    mesh = meshes.two_boxes(shared_dir / "deep_boxes.msh", n_foundation=(5, 5, 10))
    scene = _boxes_scene(mesh, mu=mu)
    condensed, solver = _solve(scene)
    direct, plain = _solve(scene, reuse_factorisation=False)
    assert plain.linear.condensed_solves == 0
    assert solver.linear.condensed_solves > 0
    assert solver.linear.factorisations == 1  # the first solve's, which prices the path
    assert solver.summary.linear_solves["condensed_solves"] == solver.linear.condensed_solves
    serial = _solve(scene, MPI.COMM_SELF)[0] if solver.comm.size > 1 else direct
    for reference in (direct, serial):
        for a, b in zip(condensed, reference):
            for group in b.reactions:
                R = np.abs(b.reactions[group]).max()  # measured: 1e-14 R
                np.testing.assert_allclose(a.reactions[group], b.reactions[group],
                                           atol=1e-10 * R)
        assert [i.iterations for i in condensed] == [i.iterations for i in reference]


def test_scene_chord_setting_reaches_newton(shared_dir):
    """``[solver] chord``: a finite-strain scene takes chord steps by default and none with
    ``chord = 0``, to the same reactions (the convergence test's precision: measured
    8e-11 of the largest) with fewer factorisations (7 against 13)."""
    mesh = meshes.two_boxes(shared_dir / "boxes.msh")
    scene = _boxes_scene(mesh, model="neo-hookean", mu=0.3)
    chord = run(scene, write=False)
    exact = run(replace(scene, solver=SolverSettings(chord=0.0)), write=False)
    solves = [r.summary.linear_solves for r in (chord, exact)]
    assert solves[0]["chord_solves"] > 0 and solves[1]["chord_solves"] == 0
    assert solves[0]["preconditioner_setups"] < solves[1]["preconditioner_setups"], solves
    for a, b in zip(chord.increments, exact.increments, strict=True):
        R = np.abs(b.reactions["block_top"]).max()
        np.testing.assert_allclose(a.reactions["block_top"], b.reactions["block_top"],
                                   atol=1e-9 * R)


def test_exchange_counts_what_the_searches_sent(shared_dir):
    """``NodeToSurface.exchange()``: per rank, the boxes allgathered (48 B each in 3D) and
    the master faces sent point to point (136 B a Q4 face); what the ranks sent is what they
    received; nothing goes between ranks serially."""
    mesh = meshes.two_boxes(shared_dir / "boxes.msh")
    _, solver = _solve(_boxes_scene(mesh, mu=0.3))
    comm = solver.comm
    ex = solver.system.contacts[0].exchange()
    assert ex.searches > 0 and comm.allreduce(ex.faces) > 0
    assert 0 < ex.box_bytes <= 48 * comm.size * ex.searches
    sent, received = comm.allreduce(ex.face_bytes_sent), comm.allreduce(ex.face_bytes_received)
    assert sent == received == 136 * comm.allreduce(ex.faces_sent)
    assert comm.allreduce(ex.faces_received) == comm.allreduce(ex.faces_sent)
    if comm.size == 1:
        assert sent == 0 and ex.gathered == 0


@pytest.mark.parametrize("mu", [0.0, 0.3])
def test_frictionless_linear_jacobian_is_symmetric_and_factorised_ldlt(shared_dir, mu):
    """Linear bodies: the Jacobian is symmetric iff the contact is frictionless
    (docs/theory.md §7.4), once its constrained columns are eliminated like its rows; the
    default solver then factorises LDL^T on one rank (LU on several: MUMPS's distributed
    LDL^T met zero pivots on some partitions) and reaches LU's reactions in LU's iterations.
    A body that is not linear is never taken as symmetric."""
    mesh = meshes.two_boxes(shared_dir / "boxes.msh")
    scene = _boxes_scene(mesh, mu=mu)
    ldlt, solver = _solve(scene)
    lu, _ = _solve(scene, petsc_options={"pc_type": "lu"})
    system = solver.system
    assert system.symmetric == (mu == 0.0)
    ldlt_expected = mu == 0.0 and MPI.COMM_WORLD.size == 1
    assert solver.linear.settings()["pc_type"] == ("cholesky" if ldlt_expected else "lu")
    J = system.jacobian(system.x, symmetric=True)
    D = J.copy()
    D.transpose()
    D.axpy(-1.0, J)
    asymmetry = D.norm(PETSc.NormType.INFINITY) / J.norm(PETSc.NormType.INFINITY)
    assert asymmetry < 1e-14 if mu == 0.0 else asymmetry > 1e-6  # measured: 6.6e-16 / 0.28
    for a, b in zip(ldlt, lu):
        for group in b.reactions:
            R = np.abs(b.reactions[group]).max()
            np.testing.assert_allclose(a.reactions[group], b.reactions[group], atol=1e-10 * R)
    assert [i.iterations for i in ldlt] == [i.iterations for i in lu]
    assert not ContactProblem(_boxes_scene(mesh, "neo-hookean", mu=0.0)).system.symmetric


@pytest.mark.parametrize("mu", [0.0, 0.3])
def test_kept_factorisation_gives_the_direct_answer(shared_dir, mu):
    """A factorisation kept as GMRES's preconditioner (SuperLU_dist's: kept whatever it
    costs, never condensed) for the whole run, across increments and the searches' new
    patterns, with Newton's inexact linear tolerance: the reactions of a factorisation per
    iteration (measured: 1e-13 R), in the same Newton iterations give or take one."""
    mesh = meshes.two_boxes(shared_dir / "boxes.msh")
    scene = _boxes_scene(mesh, mu=mu)
    kept, solver = _solve(scene, petsc_options={"pc_factor_mat_solver_type": "superlu_dist"},
                          reuse_factorisation=True)
    direct, plain = _solve(scene, reuse_factorisation=False)  # while the other one lives
    assert plain.linear.settings()["factor_solver_type"] == "mumps"
    assert solver.linear.settings()["factor_solver_type"] == "superlu_dist"
    assert solver.linear.factorisations == 1 and solver.linear.krylov_iterations > 0
    assert plain.linear.factorisations == plain.summary.newton_iterations  # cutbacks' too
    assert [i.t for i in kept] == [i.t for i in direct]
    for a, b in zip(kept, direct):
        for group in b.reactions:
            R = np.abs(b.reactions[group]).max()
            np.testing.assert_allclose(a.reactions[group], b.reactions[group], atol=1e-10 * R)
    # MUMPS against SuperLU_dist: the last increment may take one iteration more (2 ranks)
    assert all(abs(a.iterations - b.iterations) <= 1 for a, b in zip(kept, direct))


def test_factorisation_on_the_free_rows_gives_the_whole_systems_step(shared_dir):
    """A Neo-Hookean block on a linear foundation, off equilibrium: a factorisation given
    the constrained rows solves on the others only (a matrix of the free rows' size), and
    given also the foundation's interior (serial: the rows off the contact surface)
    condenses it out (a matrix of the other free rows' size), its 432 rows factorised by
    PETSc's LU or, asked by the options under ``interior_``, MUMPS; all give the step of
    the whole system's factorisation, zero in the constrained rows.  Under MPI the interior
    is empty: the free rows' solve."""
    scene = cases.press_shear_scene(meshes.blocks_on_foundation(shared_dir / "blocks.msh"))
    _, solver = _solve(scene)
    system = solver.system
    rng = np.random.default_rng(system.comm.rank)
    values = system.x.getArray()
    free = np.setdiff1d(np.arange(len(values)), system.constrained_rows)
    values[free] += 1e-3 * rng.standard_normal(len(free))
    system.x.setArray(values)
    for c in system.contacts:
        c.update(system.x)
    system.residual(system.x, system.b)
    J = system.jacobian(system.x)
    interior = system.linear_interior()
    count = system.comm.allreduce
    assert (count(len(interior)) > 0) == (system.comm.size == 1)
    held = count(len(system.constrained_rows))
    steps, packages = [], []
    rows, n_free = system.constrained_rows, system.x.getSize() - held
    database, name = PETSc.Options(), "dolfinx_friction_interior_pc_factor_mat_solver_type"
    for constrained, constant, size, package in (
            (None, None, system.x.getSize(), None), (rows, None, n_free, None),
            (rows, interior, n_free - count(len(interior)), None),
            (rows, interior, n_free - count(len(interior)), "mumps")):
        if package:
            database[name] = package
        linear, dx = LinearSolver(system.comm, reuse=False), system.x.duplicate()
        try:
            assert linear.solve(J, system.b, dx, constrained=constrained, constant=constant)
        finally:
            database.delValue(name)
        steps.append(dx.getArray().copy())
        packages.append(linear.settings().get("interior_factor_solver_type"))
        assert linear.ksp.getOperators()[0].getSize()[0] == size
    assert packages == [None, None, *(["petsc", "mumps"] if system.comm.size == 1
                                      else [None, None])]
    whole = steps[0]
    scale = system.comm.allreduce(np.abs(whole).max(), op=MPI.MAX)
    for reduced in steps[1:]:
        assert not reduced[system.constrained_rows].any()
        # measured <= 2.2e-15 (1, 2, 3 ranks; the interior by PETSc's LU or MUMPS)
        np.testing.assert_allclose(reduced, whole, atol=1e-13 * scale)


def test_live_solvers_keep_their_own_options(shared_dir):
    """Two live solvers of the same prefix read none of each other's options; options set
    under the prefix in PETSc's options database (the command line's) win over the given
    ones; none is left behind."""
    mesh = meshes.two_boxes(shared_dir / "boxes.msh")
    scene = _boxes_scene(mesh, mu=0.3)
    superlu = {"pc_type": "lu", "pc_factor_mat_solver_type": "superlu_dist"}
    _, given = _solve(scene, petsc_options=superlu)
    _, plain = _solve(scene)
    assert given.linear.settings()["factor_solver_type"] == "superlu_dist"
    assert plain.linear.settings()["factor_solver_type"] == "mumps"
    database = PETSc.Options()
    database["dolfinx_friction_pc_factor_mat_solver_type"] = "superlu_dist"
    try:
        _, chosen = _solve(scene, petsc_options={**superlu, "pc_factor_mat_solver_type": "mumps"})
    finally:
        database.delValue("dolfinx_friction_pc_factor_mat_solver_type")
    assert chosen.linear.settings()["factor_solver_type"] == "superlu_dist"
    del given, plain, chosen
    gc.collect()
    assert not [k for k in PETSc.Options().getAll() if k.startswith("dolfinx_friction_")]


def test_condensed_solve_falls_back_when_the_bulk_is_singular(shared_dir):
    """A block held by the contact alone (pressure on its top): its bulk stiffness is
    singular, the condensed path does not converge and the factorisation path answers,
    with the reactions and iterations of factorising every Jacobian."""
    mesh = meshes.two_boxes(shared_dir / "deep_boxes.msh", n_foundation=(5, 5, 10))
    scene = Scene(
        mesh=mesh, bodies=(Body("block", 1000.0, 0.3), Body("foundation", 2000.0, 0.25)),
        contacts=(ContactPair("block_bottom", "foundation_top", mu=0.3),),
        steps=(Step("press", increments=2, bcs=(BC("foundation_bottom", (0.0, 0.0, 0.0)),),
                    loads=(Load("block_top", pressure=10.0),)),))
    condensed, solver = _solve(scene)
    direct, _ = _solve(scene, reuse_factorisation=False)
    assert solver.linear.condensed_solves == 0
    for a, b in zip(condensed, direct):
        R = np.abs(b.reactions["foundation_bottom"]).max()  # measured: 1e-15 R
        np.testing.assert_allclose(a.reactions["foundation_bottom"],
                                   b.reactions["foundation_bottom"], atol=1e-10 * R)
    assert [i.iterations for i in condensed] == [i.iterations for i in direct]


def test_jacobian_splits_into_bulk_and_contact(shared_dir):
    """``split()``: the last Jacobian is exactly the bulk matrix (constrained rows made
    identity; linear bodies: the columns too, in both) plus the contact entries, all within
    the contact surfaces' dofs."""
    mesh = meshes.two_boxes(shared_dir / "boxes.msh")
    _, solver = _solve(_boxes_scene(mesh, mu=0.3), MPI.COMM_SELF)
    system = solver.system
    split = system.split()
    assert split is not None and len(split.values) > 0 and split.symmetric
    J = system.jacobian(system.x, symmetric=True)
    assert np.isin(split.rows, split.dofs).all() and np.isin(split.cols, split.dofs).all()
    D = J.copy()
    D.axpy(-1.0, split.bulk, PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
    C = PETSc.Mat().createAIJ(J.getSize(), comm=MPI.COMM_SELF)
    C.setUp()
    C.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
    for r, c, v in zip(split.rows, split.cols, split.values):
        C.setValue(r, c, v, addv=PETSc.InsertMode.ADD)
    C.assemble()
    D.axpy(-1.0, C, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    assert D.norm(PETSc.NormType.INFINITY) <= 1e-15 * J.norm(PETSc.NormType.INFINITY)


def test_slave_areas_sum_to_the_surface_area(shared_dir):
    mesh = meshes.two_boxes(shared_dir / "boxes.msh")
    problem = ContactProblem(_boxes_scene(mesh))
    block = problem.body_field("block")
    slaves = SlaveNodes(block, "block_bottom")
    assert problem.comm.allreduce(slaves.area.sum()) == pytest.approx(0.25, rel=1e-12)
    assert problem.comm.allreduce(len(slaves.nodes)) == 25


def test_master_normals_point_out_of_the_body(shared_dir):
    mesh = meshes.two_boxes(shared_dir / "boxes.msh")
    problem = ContactProblem(_boxes_scene(mesh))
    faces = master_faces(problem.body_field("foundation"), "foundation_top")
    _, dphi, _ = faces.face.evaluate(faces.face.centroid[None])
    t = np.einsum("ka,fkd->fad", dphi[0], faces.X)
    normals = np.cross(t[:, 0], t[:, 1])
    assert np.all(normals[:, 2] > 0)
    assert problem.comm.allreduce(face_areas(faces.face, faces.X).sum()) == pytest.approx(1.0)


@pytest.mark.parametrize("degree, master", [(None, "foundation"), (2, "plane")])
def test_parallel_run_matches_serial_run(shared_dir, comm, degree, master):
    """The same scene on all ranks and on one rank: reactions agree to 1e-8 relative,
    and under MPI some slave nodes pair with master faces owned by another rank (P2 on a
    plane: slave nodes spread their forces over slave faces of another rank)."""
    mesh = meshes.two_boxes(shared_dir / "boxes.msh", n_block=(5, 5, 2), n_foundation=(7, 7, 2))
    scene = _boxes_scene(mesh, degree=degree, master=master, mu=0.3)
    parallel = run(scene, write=False, comm=comm)
    serial = run(scene, write=False, comm=MPI.COMM_SELF)
    for a, b in zip(parallel.increments, serial.increments):
        for group in a.reactions:
            np.testing.assert_allclose(a.reactions[group], b.reactions[group], rtol=1e-8,
                                       atol=1e-10 * np.abs(b.reactions[group]).max())
        assert (a.active, a.slipping) == (b.active, b.slipping)
    pair = next(iter(parallel.problem.pairs.values()))
    start, end = parallel.problem.u.getOwnershipRange()
    # master columns may be remote; so may the rows of a spread slave force (P2, plane)
    rows, cols = pair.couplings()
    remote = np.concatenate([rows, cols])
    crossing = comm.allreduce(int(((remote < start) | (remote >= end)).sum()))
    if comm.size > 1:
        assert crossing > 0
    else:
        assert crossing == 0


def test_rigid_obstacle_force_control(shared_dir):
    """A rigid plane driven by force presses a block: its translation becomes an unknown and
    the force it transmits equals the prescribed one."""
    mesh = meshes.block_3d(shared_dir / "block.msh")
    force = (0.0, 0.0, 5.0)
    scene = Scene(
        mesh=mesh, bodies=(Body("block", 1000.0, 0.3),),
        rigids=(Rigid("plate", "plane", point=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0)),),
        contacts=(ContactPair("bottom", "plate"),),
        steps=(Step("touch", bcs=(BC("top", (0.0, 0.0, 0.0)),)),
               Step("push", increments=2, rigid=(RigidMotion("plate", force=force),))))
    result = run(scene, write=False)
    last = result.increments[-1]
    np.testing.assert_allclose(last.rigid_f["plate"], force, atol=1e-9)
    np.testing.assert_allclose(last.reactions["top"], -np.asarray(force), rtol=1e-8, atol=1e-9)
    assert last.rigid_u["plate"][2] > 0.0


def _stacked_scene(mesh, mu: float) -> Scene:
    """2D: the upper block pressed on the lower one and slid (``stacked``'s groups)."""
    return Scene(
        mesh=mesh, bodies=(Body("lower", 2000.0, 0.25), Body("upper", 1000.0, 0.3)),
        contacts=(ContactPair("upper_bottom", "lower_top", mu=mu),),
        steps=(Step("press", bcs=(BC("lower_bottom", (0.0, 0.0)),
                                  BC("upper_top", (0.0, -0.01)))),
               Step("slide", increments=3, bcs=(BC("upper_top", (0.02, -0.01)),))))


@pytest.mark.parametrize("mu", [0.0, 0.3])
def test_small_serial_system_is_factorised_by_petsc(shared_dir, mu):
    """A 2D system below ``NATIVE_MAX_DOFS``: on one rank PETSc's own factorisation
    (Cholesky when frictionless, LU with friction; nested dissection) of every Jacobian,
    recorded in summary.json; MUMPS on several ranks.  The reactions of MUMPS's LU to
    round-off (measured: 2.5e-15 R on 146 dofs), in the same Newton iterations."""
    from dolfinx_friction.nls.defaults import NATIVE_MAX_DOFS, factorisation
    mesh = meshes.stacked(shared_dir / "stack_native.msh", 8, 6)
    scene = _stacked_scene(mesh, mu)
    out = shared_dir / f"native_mu{mu}"
    result = run(scene, out=out)
    dofs = result.problem.system.x.getSize()
    assert dofs <= NATIVE_MAX_DOFS[2] and factorisation(dofs, 2, 2) == "mumps"
    settings = json.loads((out / "summary.json").read_text())["resolved"]["linear_solver"]
    serial = MPI.COMM_WORLD.size == 1
    assert settings["factor_solver_type"] == ("petsc" if serial else "mumps")
    if serial:
        assert settings["ordering"] == "nd" and not settings["reuse_factorisation"]
        assert settings["pc_type"] == ("cholesky" if mu == 0.0 else "lu")
    mumps, solver = _solve(scene, petsc_options={"pc_factor_mat_solver_type": "mumps"})
    assert solver.linear.settings()["factor_solver_type"] == "mumps"
    for a, b in zip(result.increments, mumps):
        for group in b.reactions:
            R = np.abs(b.reactions[group]).max()
            np.testing.assert_allclose(a.reactions[group], b.reactions[group], atol=1e-10 * R)
    assert [i.iterations for i in result.increments] == [i.iterations for i in mumps]


def test_petsc_factorisation_hands_a_failed_solve_to_mumps():
    """PETSc's LU does not pivot: a zero on the diagonal (a regular matrix) fails it, MUMPS
    solves that system and stays; a singular matrix fails both, with MUMPS's reason."""
    comm = MPI.COMM_SELF
    A = PETSc.Mat().createAIJ((3, 3), csr=([0, 2, 4, 5], [0, 1, 0, 1, 2],
                                           [0.0, 2.0, 3.0, 1.0, 4.0]), comm=comm)
    b = A.createVecLeft()
    b.setArray([2.0, 4.0, 8.0])
    x = b.duplicate()
    linear = LinearSolver(comm, package="petsc")
    assert linear.settings()["factor_solver_type"] == "petsc"
    assert linear.solve(A, b, x) and linear.failure == ""
    np.testing.assert_allclose(x.getArray(), [1.0, 1.0, 2.0], rtol=1e-14)
    assert linear.settings()["factor_solver_type"] == "mumps"
    singular = PETSc.Mat().createAIJ((2, 2), csr=([0, 2, 4], [0, 1, 0, 1],
                                                  [1.0, 1.0, 1.0, 1.0]), comm=comm)
    b, x = singular.createVecLeft(), singular.createVecLeft()
    b.setArray([1.0, 2.0])
    linear = LinearSolver(comm, package="petsc")
    assert not linear.solve(singular, b, x)
    assert "singular Jacobian" in linear.failure
    assert linear.settings()["factor_solver_type"] == "mumps"
    with pytest.raises(ValueError, match="package"):
        LinearSolver(comm, package="umfpack")
