"""The contact in dolfinx 0.10+'s SNES idiom (``add_contact`` on a user's
``fem.petsc.NonlinearProblem``): the same answer as the package's own block problem, the
user's history committed and rolled back with the contact's, and one clear line for bad
input.  Serial and under ``mpirun -n 2``; skipped below dolfinx 0.10 (where the package
says so in one line, tested too)."""
from __future__ import annotations

import inspect

import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh
from dolfinx.fem.petsc import NonlinearProblem
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx_friction import (BlockProblem, ContactSetupError, NodeToSurface, Surface,
                              add_contact, rigid_plane, snes_solve)
from tests.fem.test_contact_api import block as rectangle
from tests.fem.test_contact_api import neo_hookean
from tests.fem.test_postcondition import Counter  # a user's history

SNES_PROBLEM = "petsc_options_prefix" in inspect.signature(NonlinearProblem).parameters
needs_snes = pytest.mark.skipif(not SNES_PROBLEM,
                                reason="dolfinx < 0.10: no SNES NonlinearProblem")
BOTTOM, TOP = 1, 2
E, NU = 1000.0, 0.3
OPTIONS = {"snes_type": "newtonls", "snes_linesearch_type": "bt", "snes_rtol": 1e-10,
           "snes_atol": 1e-9, "snes_max_it": 50, "ksp_type": "preonly", "pc_type": "lu",
           "pc_factor_mat_solver_type": "mumps"}
LOADS = [(0.0, 0.02), (0.0, 0.04), (0.02, 0.04), (0.05, 0.04)]  # press, then slide


def block():
    """A Neo-Hookean block (1 x 0.5, 8 x 4 cells) held at its top: V, tags, u, F, bc."""
    domain = mesh.create_rectangle(MPI.COMM_WORLD, [[0.0, 0.0], [1.0, 0.5]], [8, 4],
                                   mesh.CellType.quadrilateral)
    facets, values = [], []
    for y, tag in ((0.0, BOTTOM), (0.5, TOP)):
        found = mesh.locate_entities_boundary(domain, 1, lambda x, y=y: np.isclose(x[1], y))
        facets.append(found)
        values.append(np.full(len(found), tag, dtype=np.int32))
    order = np.argsort(np.concatenate(facets))
    tags = mesh.meshtags(domain, 1, np.concatenate(facets)[order],
                         np.concatenate(values)[order])
    V = fem.functionspace(domain, ("Lagrange", 1, (2,)))
    u, v = fem.Function(V), ufl.TestFunction(V)
    mu, kappa = E / (2 * (1 + NU)), E / (3 * (1 - 2 * NU))
    F2 = ufl.variable(ufl.Identity(2) + ufl.grad(u))
    F3 = ufl.as_matrix([[F2[0, 0], F2[0, 1], 0], [F2[1, 0], F2[1, 1], 0], [0, 0, 1]])
    J = ufl.det(F3)
    W = mu / 2 * (J ** (-2 / 3) * ufl.tr(F3.T * F3) - 3) + kappa / 2 * (J - 1) ** 2
    F = ufl.inner(ufl.diff(W, F2), ufl.grad(v)) * ufl.dx
    held = fem.dirichletbc(np.zeros(2), fem.locate_dofs_topological(V, 1, tags.find(TOP)), V)
    return V, tags, u, F, held


def pair_on(V, tags):
    return NodeToSurface(Surface(V, tags, BOTTOM), rigid_plane([0.0, 0.0], [0.0, 1.0]), E=E,
                         K=100 * E / 0.125, stick_slope=10 * E / 0.125, mu=0.3)


@needs_snes
def test_snes_idiom_gives_the_block_problems_answer():
    """Press and slide, increment by increment: the contact force through add_contact on
    the user's NonlinearProblem equals the package's BlockProblem + snes_solve to 1e-8."""
    V, tags, u, F, held = block()
    pair = pair_on(V, tags)
    problem = NonlinearProblem(F, u, bcs=[held], petsc_options_prefix="test_idiom_",
                               petsc_options=OPTIONS)
    log = Counter()
    contact = add_contact(problem, [pair], bcs=[held], history=[log])
    V2, tags2, u2, F2, held2 = block()
    pair2 = pair_on(V2, tags2)
    reference = BlockProblem([F2], [u2], [held2], [pair2])
    for load in LOADS:
        pair.obstacle_translation = load
        assert contact.solve() > 0
        pair2.obstacle_translation = load
        pair2.begin(reference.x)
        assert snes_solve(reference, options=OPTIONS).getConvergedReason() > 0
        pair2.commit()
        f, f2 = pair.force(), pair2.force()
        np.testing.assert_allclose(f, f2, rtol=0.0, atol=1e-8 * np.abs(f2).max())
    assert log.commits == len(LOADS) and log.rollbacks == 0
    assert abs(f[0] / f[1]) > 0.1  # the slide reached friction


@needs_snes
def test_augmented_contacts_are_solved_again_until_their_overclosure_is_gone():
    """``method="augmented"``: SNESContact.solve updates the multipliers and solves again
    until the overclosure is below 1e-4 of the spacing (the penalty leaves 1e-2 here), in
    every increment of the press and slide; each increment is committed once."""
    V, tags, u, F, held = block()
    plane = rigid_plane([0.0, 0.0], [0.0, 1.0])
    penalty = NodeToSurface(Surface(V, tags, BOTTOM), plane, E=E, mu=0.3)
    problem = NonlinearProblem(F, u, bcs=[held], petsc_options_prefix="test_penalty_",
                               petsc_options=OPTIONS)
    contact = add_contact(problem, [penalty], bcs=[held])
    penalty.obstacle_translation = LOADS[0]
    assert contact.solve() > 0 and penalty.penetration() > 1e-3
    del contact
    V, tags, u, F, held = block()
    pair = NodeToSurface(Surface(V, tags, BOTTOM), plane, E=E, mu=0.3, method="augmented")
    problem = NonlinearProblem(F, u, bcs=[held], petsc_options_prefix="test_augmented_",
                               petsc_options=OPTIONS)
    log = Counter()
    contact = add_contact(problem, [pair], bcs=[held], history=[log])
    for load in LOADS:
        pair.obstacle_translation = load
        assert contact.solve() > 0
        assert pair.penetration() <= 1e-4
        assert not pair.augment()  # nothing left to update
    assert (log.commits, log.rollbacks) == (len(LOADS), 0)


class StalePairing(NodeToSurface):
    """A pair that always reports a stale pairing (as one converged on pairings frozen far
    from the answer: NodeToSurface.stale_pairing, tested on its own in test_contact_api)."""

    def stale_pairing(self) -> int:
        return 1


@needs_snes
def test_an_increment_converged_on_a_stale_pairing_is_rolled_back():
    """SNES converges, but a pair's pairing is stale: solve() returns DIVERGED_MAX_IT,
    rolls the contact's and the user's history back, and leaves the solution at the
    increment's start (the user's loop cuts the increment back)."""
    V, tags, u, F, held = block()
    pair = StalePairing(Surface(V, tags, BOTTOM), rigid_plane([0.0, 0.0], [0.0, 1.0]), E=E,
                        mu=0.3)
    problem = NonlinearProblem(F, u, bcs=[held], petsc_options_prefix="test_stale_",
                               petsc_options=OPTIONS)
    log = Counter()
    contact = add_contact(problem, [pair], bcs=[held], history=[log])
    pair.obstacle_translation = LOADS[0]
    assert contact.solve() == PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT
    assert (log.commits, log.rollbacks) == (0, 1)
    assert MPI.COMM_WORLD.allreduce(np.abs(u.x.array).max(initial=0.0), op=MPI.MAX) == 0.0


def two_bodies():
    """A Neo-Hookean block (quadrilaterals) pressed by its top onto a Neo-Hookean
    foundation (triangles, held at its bottom) and dragged: the residuals, unknowns,
    Dirichlet conditions, the surfaces (block's bottom, foundation's top) and the block's
    top displacement."""
    Vb, tb = rectangle(0.2, 0.4, 0.6, 0.3, 6, 3)
    Vf, tf = rectangle(0.0, 0.0, 1.0, 0.4, 9, 4, mesh.CellType.triangle)
    ub, uf = fem.Function(Vb), fem.Function(Vf)
    top = fem.Constant(Vb.mesh, np.zeros(2))
    bcs = [fem.dirichletbc(top, fem.locate_dofs_topological(Vb, 1, tb.find(TOP)), Vb),
           fem.dirichletbc(np.zeros(2), fem.locate_dofs_topological(Vf, 1, tf.find(BOTTOM)),
                           Vf)]
    residuals = [neo_hookean(ub, ufl.TestFunction(Vb)), neo_hookean(uf, ufl.TestFunction(Vf))]
    return residuals, [ub, uf], bcs, (Surface(Vb, tb, BOTTOM), Surface(Vf, tf, TOP)), top


def pair_between(surfaces, spaces):
    return NodeToSurface(*surfaces, spaces=spaces, E=E, K=100 * E / 0.1,
                         stick_slope=10 * E / 0.1, mu=0.3)


@needs_snes
def test_two_bodies_as_blocks_give_the_block_problems_answer():
    """Two meshes as a block NonlinearProblem (lists of forms, kind="mpi", the Jacobian's
    off-diagonal blocks None): the couplings between the blocks in the matrix, every
    increment's contact force equal to BlockProblem + snes_solve to 1e-8."""
    F, u, bcs, surfaces, top = two_bodies()
    pair = pair_between(surfaces, [w.function_space for w in u])
    J = [[ufl.derivative(F[0], u[0]), None], [None, ufl.derivative(F[1], u[1])]]
    problem = NonlinearProblem(F, u, bcs=bcs, J=J, kind="mpi",
                               petsc_options_prefix="test_blocks_", petsc_options=OPTIONS)
    contact = add_contact(problem, [pair], bcs=bcs)
    F2, u2, bcs2, surfaces2, top2 = two_bodies()
    pair2 = pair_between(surfaces2, [w.function_space for w in u2])
    reference = BlockProblem(F2, u2, bcs2, [pair2])
    for load in [(0.0, -0.01), (0.0, -0.03), (0.01, -0.03), (0.02, -0.03)]:
        top.value[:] = load
        assert contact.solve() > 0
        top2.value[:] = load
        reference.apply_bcs()
        pair2.begin(reference.x)
        assert snes_solve(reference, options=OPTIONS).getConvergedReason() > 0
        pair2.commit()
        f, f2 = pair.force(), pair2.force()
        np.testing.assert_allclose(f, f2, rtol=0.0, atol=1e-8 * np.abs(f2).max())
    assert abs(f[0]) > 0.1 * abs(f[1])  # the drag is carried by friction
    with pytest.raises(ContactSetupError, match="its spaces are not the problem's"):
        add_contact(problem, [pair_between(surfaces, [w.function_space for w in u[::-1]])])


@needs_snes
def test_a_failed_increment_rolls_back_the_users_history():
    """One SNES iteration allowed on a slide increment: it fails, the user's history and
    the contact's are rolled back and the displacement is that of the increment's start;
    so too where SNES raises on the failure (snes_error_if_not_converged); the increment
    then succeeds with the iterations it needs."""
    V, tags, u, F, held = block()
    pair = pair_on(V, tags)
    problem = NonlinearProblem(F, u, bcs=[held], petsc_options_prefix="test_rollback_",
                               petsc_options=OPTIONS)
    log = Counter()
    contact = add_contact(problem, [pair], bcs=[held], history=[log])
    pair.obstacle_translation = (0.0, 0.04)
    assert contact.solve() > 0
    start = u.x.array.copy()
    pair.obstacle_translation = (0.05, 0.04)
    contact.snes.setTolerances(max_it=1)
    assert contact.solve() <= 0
    assert (log.commits, log.rollbacks) == (1, 1)
    np.testing.assert_array_equal(u.x.array, start)
    contact.snes.setErrorIfNotConverged(True)  # the failure raised: rolled back as well
    with pytest.raises(Exception):
        contact.solve()
    assert (log.commits, log.rollbacks) == (1, 2)
    np.testing.assert_array_equal(u.x.array, start)
    contact.snes.setErrorIfNotConverged(False)
    contact.snes.setTolerances(max_it=50)
    assert contact.solve() > 0
    assert (log.commits, log.rollbacks) == (2, 2)


@needs_snes
def test_bad_input_gets_one_clear_line():
    V, tags, u, F, held = block()
    problem = NonlinearProblem(F, u, bcs=[held], petsc_options_prefix="test_bad_",
                               petsc_options=OPTIONS)
    W, wtags, *_ = block()  # another space
    with pytest.raises(ContactSetupError, match="its spaces are not the problem's"):
        add_contact(problem, [pair_on(W, wtags)])
    with pytest.raises(ContactSetupError, match="has no commit"):
        add_contact(problem, [pair_on(V, tags)], history=[object()])
    pair = pair_on(V, tags)
    contact = add_contact(problem, [pair], bcs=[held])
    with pytest.raises(ContactSetupError, match="already has contacts"):
        add_contact(problem, [pair_on(V, tags)])
    with pytest.raises(Exception) as info:  # SNES reports it as a PETSc error, chained
        problem.solve()
    assert "have not begun this increment" in str(info.value.__cause__ or info.value.__context__
                                                   or info.value)
    pair.obstacle_translation = (0.0, 0.02)
    contact.begin()  # the problem's own matrix back in SNES: no slots for the couplings
    contact.snes.setJacobian(contact.snes.getJacobian()[2][0], problem.A, problem.A)
    with pytest.raises(Exception) as info:
        problem.solve()
    assert "the matrix has no slots for the current contact couplings" in str(
        info.value.__cause__ or info.value.__context__ or info.value)
    del contact
    scalar = fem.functionspace(V.mesh, ("Lagrange", 1))
    with pytest.raises(ContactSetupError, match="the function space has 1 component"):
        pair_on(scalar, tags)
    with pytest.raises(ContactSetupError, match="is not a dolfinx.fem.petsc.NonlinearProblem"):
        add_contact(object(), [])
    # dolfinx 0.11 leaves petsc_options in PETSc's options database (its del ignores the
    # pushed prefix): a prefix no solver of the package uses, and the options removed after
    clash = NonlinearProblem(F, u, bcs=[held], petsc_options_prefix="dolfinx_friction_user_",
                             petsc_options=OPTIONS)
    with pytest.raises(ContactSetupError, match="options prefix 'dolfinx_friction_user_' is"):
        add_contact(clash, [pair_on(V, tags)])
    options = PETSc.Options()
    for key in [k for k in options.getAll() if k.startswith("dolfinx_friction_user_")]:
        options.delValue(key)


@pytest.mark.skipif(SNES_PROBLEM, reason="dolfinx >= 0.10 has the SNES NonlinearProblem")
def test_older_dolfinx_is_told_in_one_line():
    with pytest.raises(ContactSetupError, match=r"add_contact needs dolfinx >= 0.10"):
        add_contact(object(), [])
