"""The public contact API on the user's own dolfinx spaces and UFL residuals.

Neo-Hookean bodies (CalculiX's NEO HOOKE, plane strain) on a rigid plane and on a
deformable Neo-Hookean foundation, through ``NodeToSurface`` + ``BlockProblem``: the
global Jacobian against central differences of the global residual, quadratic
convergence, SNES against the project's Newton, the user's own Newton loop against
``solve_steps``, and one-line errors for bad input.  Serial and under ``mpirun -n 2``.
"""
from __future__ import annotations

import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx_friction import (NO_ELEMENT, BlockProblem, ContactSetupError, Newton, NodeToSurface,
                              SNESNewton, Surface, create_matrix, rigid_cylinder, rigid_plane,
                              rigid_sdf, rigid_sphere, snes_solve, solve_steps)
from dolfinx_friction import _compat as compat
from tests.finite_differences import coordinate_noise, random_directions, tangent_error

E, NU = 1000.0, 0.3
BOTTOM, TOP = 1, 2


def neo_hookean(u, v):
    """Plane-strain residual of W = C10 (I1bar - 3) + (J - 1)^2 / D1 (CalculiX)."""
    mu, kappa = E / (2 * (1 + NU)), E / (3 * (1 - 2 * NU))
    F2 = ufl.variable(ufl.Identity(2) + ufl.grad(u))
    F = ufl.as_matrix([[F2[0, 0], F2[0, 1], 0], [F2[1, 0], F2[1, 1], 0], [0, 0, 1]])
    J = ufl.det(F)
    W = mu / 2 * (J ** (-2 / 3) * ufl.tr(F.T * F) - 3) + kappa / 2 * (J - 1) ** 2
    return ufl.inner(ufl.diff(W, F2), ufl.grad(v)) * ufl.dx


def block(x0, y0, width, height, nx, ny, cell=mesh.CellType.quadrilateral, degree=1):
    """A rectangle with its bottom edge tagged BOTTOM and top edge TOP."""
    m = mesh.create_rectangle(MPI.COMM_WORLD, [[x0, y0], [x0 + width, y0 + height]], [nx, ny],
                              cell)
    facets, values = [], []
    for y, tag in ((y0, BOTTOM), (y0 + height, TOP)):
        f = mesh.locate_entities_boundary(m, 1, lambda x, y=y: np.isclose(x[1], y))
        facets.append(f)
        values.append(np.full(len(f), tag, dtype=np.int32))
    facets, values = np.concatenate(facets), np.concatenate(values)
    order = np.argsort(facets)
    tags = mesh.meshtags(m, 1, facets[order].astype(np.int32), values[order])
    V = compat.vector_space(m, degree)
    return V, tags


def on_plane(degree=1, cell=mesh.CellType.quadrilateral, mu=0.3, pairing_iterations=8):
    """A Neo-Hookean block (8 x 4 cells, 1 x 0.5) held at its top, on a rigid plane that
    rises and slides."""
    V, tags = block(0.0, 0.0, 1.0, 0.5, 8, 4, cell, degree)
    u = fem.Function(V)
    held = fem.dirichletbc(np.zeros(2), fem.locate_dofs_topological(V, 1, tags.find(TOP)), V)
    contact = NodeToSurface(Surface(V, tags, BOTTOM), rigid_plane([0, 0], [0, 1]), E=E,
                            K=100 * E / 0.125, stick_slope=10 * E / 0.125, mu=mu,
                            pairing_iterations=pairing_iterations)
    return BlockProblem([neo_hookean(u, ufl.TestFunction(V))], [u], [held], [contact]), contact


def block_and_foundation(degree=1, length=1) -> tuple:
    """The spaces and facet tags ``(Vb, tb, Vf, tf)`` of :func:`two_bodies`."""
    return (block(0.2, 0.4, 0.6, 0.3, 6, 3, degree=degree)
            + block(0.0, 0.0, length, 0.4, 9 * length, 4, mesh.CellType.triangle, degree))


def two_bodies(mu=0.3, degree=1, distribution="nodal", length=1, spaces=None):
    """A Neo-Hookean block pressed by its top onto a Neo-Hookean foundation and slid (the
    foundation ``length`` times 1 long, 9 faces per unit length), on ``spaces`` (those of
    :func:`block_and_foundation`) or new ones.  Two problems whose vectors are compared
    entry by entry need the same spaces: two meshes made alike need not be partitioned
    alike (Debian sid's dolfinx 0.11 on 2 ranks now and then is not)."""
    Vb, tb, Vf, tf = spaces or block_and_foundation(degree, length)
    ub, uf = fem.Function(Vb), fem.Function(Vf)
    g = fem.Constant(Vb.mesh, np.zeros(2))
    bcs = [fem.dirichletbc(g, fem.locate_dofs_topological(Vb, 1, tb.find(TOP)), Vb),
           fem.dirichletbc(np.zeros(2), fem.locate_dofs_topological(Vf, 1, tf.find(BOTTOM)),
                           Vf)]
    contact = NodeToSurface(Surface(Vb, tb, BOTTOM), Surface(Vf, tf, TOP), E=E,
                            K=100 * E / 0.1, stick_slope=10 * E / 0.1, mu=mu,
                            distribution=distribution)
    residuals = [neo_hookean(ub, ufl.TestFunction(Vb)), neo_hookean(uf, ufl.TestFunction(Vf))]
    return BlockProblem(residuals, [ub, uf], bcs, [contact]), contact, g


def press_and_slide(problem, contact, g=None, depth=0.03, slide=0.02, increments=(3, 2)):
    def press(t):
        if g is None:
            contact.obstacle_translation = (0.0, depth * t)
        else:
            g.value[:] = (0.0, -depth * t)

    def drag(t):
        if g is None:
            contact.obstacle_translation = (slide * t, depth)
        else:
            g.value[:] = (slide * t, -depth)
    records = solve_steps(problem, press, increments[0])
    return records + solve_steps(problem, drag, increments[1])


def fd_error(problem, contact, seed=0) -> float:
    """The worst error of the Jacobian against extrapolated central differences along 3
    random directions without a kink (:mod:`tests.finite_differences`) at a perturbed
    iterate (mixed stick/slip, pairing frozen; the same on any number of ranks)."""
    rng = np.random.default_rng(seed + MPI.COMM_WORLD.rank)
    start = problem.x.copy()
    scale = MPI.COMM_WORLD.allreduce(np.abs(start.getArray()).max(initial=0.0), op=MPI.MAX)
    problem.x.setArray(start.getArray() + 1e-3 * scale * coordinate_noise(problem, seed))
    problem.apply_bcs()
    x = problem.x.copy()
    for c in problem.contacts:
        c.begin(x, start=start)
        c.update(x)
    A = problem.jacobian(x)

    def residual(y: PETSc.Vec) -> PETSc.Vec:
        b = y.duplicate()
        contact.update(y, pairing=False)
        problem.residual(y, b)
        return b
    directions = random_directions(x, rng, held=problem.constrained_rows)
    return tangent_error(residual, x, A, directions, 1e-6 * scale)


def assert_sparse_tangent(contact) -> None:
    """The sparse form of the tangent (what the one-pass fill beside a finite-strain body
    adds) holds the dense one's values, and the dense one is zero elsewhere."""
    index, values = contact.coupling_entries()
    dense = contact.coupling_values()
    elsewhere = np.ones(len(dense), bool)
    elsewhere[index] = False
    assert len(index) and np.allclose(values, dense[index], rtol=1e-14, atol=0.0)
    assert not dense[elsewhere].any()


def statuses(contact) -> set:
    found = set(contact.state().status.tolist())
    return set().union(*MPI.COMM_WORLD.allgather(found))


@pytest.mark.parametrize("degree, cell", [(1, mesh.CellType.quadrilateral),
                                          (2, mesh.CellType.triangle)])
def test_jacobian_on_rigid_plane_matches_central_differences(degree, cell):
    problem, contact = on_plane(degree, cell)
    press_and_slide(problem, contact, slide=0.02, increments=(2, 1))
    err = fd_error(problem, contact)
    print(f"\nNeo-Hookean P{degree} on a rigid plane, mu = 0.3: FD rel error {err:.2e}, "
          f"statuses {sorted(statuses(contact))}")
    assert {1, 2} <= statuses(contact)  # stick and slip nodes both tested
    assert err < 1e-7


@pytest.mark.parametrize("degree, distribution, mu", [(1, "nodal", 0.3), (2, "nodal", 0.3),
                                                     (1, "mortar", 0.3), (1, "mortar", 0.0),
                                                     (2, "mortar", 0.3)])
def test_jacobian_two_bodies_matches_central_differences(degree, distribution, mu):
    """Also with quadratic (3-node) slave edges, whose slave forces spread over the edges
    around each slave node (across ranks under MPI), and with the mortar distribution of
    the slave forces over the master (its weights held in the increment; the block's
    quadrilaterals on the foundation's triangles; P2: the slave forces spread over the
    slave edges too)."""
    problem, contact, g = two_bodies(mu=mu, degree=degree, distribution=distribution)
    press_and_slide(problem, contact, g, depth=0.02, slide=0.02, increments=(2, 1))
    err = fd_error(problem, contact)
    print(f"\nNeo-Hookean block on a Neo-Hookean foundation, P{degree}, {distribution}, "
          f"mu = {mu}: FD rel error {err:.2e}, statuses {sorted(statuses(contact))}")
    assert ({1, 2} if mu > 0 else {2}) <= statuses(contact)
    assert err < 1e-7
    assert_sparse_tangent(contact)


@pytest.mark.parametrize("distribution", ["nodal", "mortar"])
def test_the_matrix_pattern_survives_a_slide_while_the_couplings_stay_within_it(distribution):
    """The block slid by 5.4 master faces in 12 increments (cut back to 21-24) on a longer
    foundation: a search makes the matrix again (``couplings_version``) only where the
    candidates or the mortar weights couple outside its pattern, the couplings of a wider
    search: measured 6 renewals in 21 (nodal) and in 24 (mortar) increments on 1 rank, 12
    and 14 of 21 (nodal), 10 and 13 of 24 (mortar) on 2 and 3 ranks (a rank holds the master faces near its own slave
    nodes only: at its edge the wider search sees no more than the candidates'), where
    every increment renewed it before (21 of 21); the matrix of a renewed pattern has the
    slots of the tangent, which stays exact against central differences."""
    problem, contact, g = two_bodies(distribution=distribution, length=2)
    versions = []

    def press(t):
        g.value[:] = (0.0, -0.02 * t)

    def drag(t):
        g.value[:] = (0.6 * t, -0.02)
    solve_steps(problem, press, 2)
    start = contact.couplings_version
    solve_steps(problem, drag, 12,
                on_increment=lambda record: versions.append(contact.couplings_version))
    renewals = versions[-1] - start
    print(f"\n{distribution}: {renewals} renewals of the pattern in {len(versions)} slide "
          f"increments")
    assert 2 <= renewals <= 3 * len(versions) // 4
    assert fd_error(problem, contact) < 1e-7


def on_turning_obstacle(d: int, obstacle, mu=0.3, n=16):
    """A linear-elastic block (2D: 1 x 0.5, n x 8 quadrilaterals; 3D: 1 x 1 x 0.5, 6 x 6 x 3
    hexahedra) held at its top, its bottom the slave of a rigid ``obstacle`` below it."""
    if d == 3:
        m = mesh.create_box(MPI.COMM_WORLD, [[0, 0, 0], [1, 1, 0.5]], [6, 6, 3],
                            mesh.CellType.hexahedron)
        facets = [mesh.locate_entities_boundary(m, 2, lambda x, z=z: np.isclose(x[2], z))
                  for z in (0.0, 0.5)]
        order = np.argsort(np.concatenate(facets))
        tags = mesh.meshtags(m, 2, np.concatenate(facets)[order].astype(np.int32),
                             np.concatenate([np.full(len(f), t, np.int32) for f, t
                                             in zip(facets, (BOTTOM, TOP))])[order])
        V, h = compat.vector_space(m, 1), 1 / 6
    else:
        (V, tags), h = block(0.0, 0.0, 1.0, 0.5, n, 8), 1 / n
    u, v = fem.Function(V), ufl.TestFunction(V)
    lam, G = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    eps = ufl.sym(ufl.grad(u))
    F = ufl.inner(2 * G * eps + lam * ufl.tr(eps) * ufl.Identity(d), ufl.grad(v)) * ufl.dx
    held = fem.dirichletbc(np.zeros(d), fem.locate_dofs_topological(V, d - 1, tags.find(TOP)), V)
    contact = NodeToSurface(Surface(V, tags, BOTTOM), obstacle, E=E, K=100 * E / h,
                            stick_slope=10 * E / h, mu=mu)
    return BlockProblem([F], [u], [held], [contact]), contact


#: obstacles below the block that turn while they press it: (dimension, obstacle, pressing
#: translation, final translation, rotation, elements along x in 2D); stick and slip nodes
#: both at the perturbed iterate, on 1 and 2 ranks
TURNING = {
    "circle": (2, rigid_sphere([0.5, -1.0], 1.0), (0.0, 0.02), (0.02, 0.02), 0.05, 16),
    "circle-turning-only": (2, rigid_sphere([0.5, -1.0], 1.0), (0.0, 0.02), (0.0, 0.02),
                            -0.004, 32),
    "plane-about-a-point": (2, rigid_plane([0.0, 0.0], [0.0, 1.0], reference=[0.5, -0.5]),
                            (0.0, 0.02), (0.01, 0.02), 0.008, 16),
    "sphere": (3, rigid_sphere([0.5, 0.5, -1.0], 1.0), (0.0, 0.0, 0.03), (0.01, 0.0, 0.03),
               (0.01, 0.02, 0.03), 0),
    "cylinder": (3, rigid_cylinder([0.5, 0.5, -1.0], [0.0, 1.0, 0.0], 1.0),
                 (0.0, 0.0, 0.02), (0.01, 0.0, 0.02), (0.0, -0.01, 0.02), 0),
}


@pytest.mark.parametrize("case", list(TURNING))
def test_jacobian_on_a_turning_obstacle_matches_central_differences(case):
    """The slip against a rotating obstacle follows its material points: a constant of the
    increment, so the tangent stays exact (the FD check of the translating plane)."""
    d, obstacle, press_to, end, rotation, n = TURNING[case]
    problem, contact = on_turning_obstacle(d, obstacle, n=n)

    def press(t):
        contact.obstacle_translation = np.multiply(t, press_to)

    def turn(t):
        contact.obstacle_translation = np.add(press_to, np.multiply(t, np.subtract(end, press_to)))
        contact.obstacle_rotation = np.multiply(t, rotation)
    solve_steps(problem, press, 2)
    solve_steps(problem, turn, 2)
    err = fd_error(problem, contact)
    print(f"\n{case}: FD rel error {err:.2e}, statuses {sorted(statuses(contact))}")
    assert {1, 2} <= statuses(contact)
    assert err < 1e-7


def test_mortar_node_without_weights_hands_its_force_over_nodally():
    """A slave node whose faces met no master face at the increment's start (no weights)
    gives the master the nodal shares of its force: the residual of the plain
    node-to-surface pair.  The increment starts (``begin(x, start=away)``) with the block
    moved 10 sideways, off the foundation, so no slave node has weights; it starting at the
    pressed state itself, the weights act."""
    spaces = block_and_foundation()
    problem, contact, g = two_bodies(mu=0.0, distribution="nodal", spaces=spaces)
    press_and_slide(problem, contact, g, depth=0.02, slide=0.01, increments=(1, 1))
    mortar, contact_m, g_m = two_bodies(mu=0.0, distribution="mortar", spaces=spaces)
    g_m.value[:] = g.value
    x = mortar.x
    x.setArray(problem.x.getArray())
    away = x.copy()
    values = away.getArray()
    values[mortar.block_slice(0)][0::2] += 10.0
    away.setArray(values)

    def residual(problem, contact, start) -> PETSc.Vec:
        """The residual at x of an increment started from ``start``."""
        contact.begin(x, start=start)
        contact.update(x)
        b = x.duplicate()
        problem.residual(x, b)
        return b
    b_nodal = residual(problem, contact, away)
    b_without, b_with = residual(mortar, contact_m, away), residual(mortar, contact_m, x)
    force = np.abs(contact.state().normal_force).max(initial=0.0)
    force = MPI.COMM_WORLD.allreduce(force, op=MPI.MAX)  # the scale of the contact rows
    assert force > 0.0
    b_without.axpy(-1.0, b_nodal)
    assert b_without.norm(PETSc.NormType.INFINITY) < 1e-10 * force, \
        worst_rows(mortar, b_without, b_nodal, [contact, contact_m])
    b_with.axpy(-1.0, b_nodal)
    assert b_with.norm(PETSc.NormType.INFINITY) > 1e-3 * force  # the weights do act


def test_a_new_condition_at_a_freed_ones_address_masks_its_own_rows():
    """The rows of the Dirichlet conditions given to :meth:`add_residual` are left out; the
    pair keeps them from one call to the next, and a condition made after the last one
    was freed (Python often gives it the freed object's address, its ``id``: 14 of 156
    rows were wrong when the pair kept the ids) masks its own rows, not the freed one's."""
    spaces = block_and_foundation()
    Vb, tb, Vf, tf = spaces
    problem, contact, g = two_bodies(mu=0.0, spaces=spaces)
    press_and_slide(problem, contact, g, depth=0.02, slide=0.01, increments=(1, 1))

    def on(V, tags, tag):
        return fem.dirichletbc(np.zeros(2), fem.locate_dofs_topological(V, 1, tags.find(tag)), V)

    def residual(bcs) -> np.ndarray:
        b = problem.x.duplicate()
        b.set(0.0)
        contact.add_residual(b, bcs)
        return b.getArray().copy()

    expected = residual([on(Vb, tb, BOTTOM)])  # the slave nodes' rows left out
    assert MPI.COMM_WORLD.allreduce(np.abs(residual([]) - expected).max(initial=0.0),
                                    op=MPI.MAX) > 0.0
    freed = on(Vf, tf, BOTTOM)  # no contact rows
    residual([freed])
    address = id(freed)
    del freed
    made = [on(Vb, tb, BOTTOM) for _ in range(100)]  # all kept: each at another address
    for bc in [bc for bc in made if id(bc) == address] + made[-1:]:
        np.testing.assert_array_equal(residual([bc]), expected)


def worst_rows(problem, difference: PETSc.Vec, b: PETSc.Vec, contacts) -> str:
    """A failure's description: this rank's row of ``difference``'s largest entry (its body,
    its node's coordinates, ``b`` there) and the largest normal force of each contact."""
    values = difference.getArray()
    if not len(values):
        return "no rows on this rank"
    row = int(np.argmax(np.abs(values)))
    body = next(k for k in range(len(problem.spaces)) if problem.block_slice(k).start <= row
                < problem.block_slice(k).stop)
    V, d = problem.spaces[body], problem.gdim
    node = (row - problem.block_slice(body).start) // d
    forces = [float(np.abs(c.state().normal_force).max(initial=0.0)) for c in contacts]
    return (f"rank {MPI.COMM_WORLD.rank}: row {row} (body {body}, node at "
            f"{V.tabulate_dof_coordinates()[node]}, component {row % d}): difference "
            f"{values[row]:.6g}, residual {b.getArray()[row]:.6g}; largest normal forces "
            f"{forces}")


def box_3d(x0, z0, width, height, n, cell, comm=MPI.COMM_WORLD):
    """A box [x0, x0 + width]^2 x [z0, z0 + height] of n x n x max(n // 2, 1) cells with its
    bottom face tagged BOTTOM and top face TOP, and its linear-elastic residual."""
    m = mesh.create_box(comm, [[x0, x0, z0], [x0 + width, x0 + width, z0 + height]],
                        [n, n, max(n // 2, 1)], cell)
    facets = [mesh.locate_entities_boundary(m, 2, lambda x, z=z: np.isclose(x[2], z))
              for z in (z0, z0 + height)]
    order = np.argsort(np.concatenate(facets))
    tags = mesh.meshtags(m, 2, np.concatenate(facets)[order].astype(np.int32),
                         np.concatenate([np.full(len(f), t, np.int32) for f, t
                                         in zip(facets, (BOTTOM, TOP))])[order])
    V = compat.vector_space(m, 1)
    u, v = fem.Function(V), ufl.TestFunction(V)
    lam, G = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    eps = ufl.sym(ufl.grad(u))
    F = ufl.inner(2 * G * eps + lam * ufl.tr(eps) * ufl.Identity(3), ufl.grad(v)) * ufl.dx
    return V, tags, u, F


def _mortar_residual_by_node(comm) -> np.ndarray:
    """A hexahedral block on a tetrahedral foundation, mortar distribution, the block's
    nodes moved by a field of their coordinates into the foundation: every node's
    coordinates and its residual, (n_nodes, 6) for both bodies, sorted by the coordinates."""
    Vb, tb, ub, Fb = box_3d(0.25, 0.3, 0.5, 0.2, 4, mesh.CellType.hexahedron, comm)
    Vf, tf, uf, Ff = box_3d(0.0, 0.0, 1.0, 0.3, 5, mesh.CellType.tetrahedron, comm)
    contact = NodeToSurface(Surface(Vb, tb, BOTTOM), Surface(Vf, tf, TOP), E=E,
                            distribution="mortar")
    problem = BlockProblem([Fb, Ff], [ub, uf], [], [contact])
    ub.interpolate(lambda X: np.stack([0.01 * X[1], -0.02 * X[0], -0.004 - 0.01 * X[0] * X[1]]))
    problem.gather()
    contact.begin(problem.x)
    contact.update(problem.x)
    b = problem.x.duplicate()
    problem.residual(problem.x, b)
    assert comm.allreduce(int(np.count_nonzero(contact.state().normal_force))) > 10
    rows = []
    for k, V in enumerate((Vb, Vf)):
        n = V.dofmap.index_map.size_local
        rows.append(np.hstack([V.tabulate_dof_coordinates()[:n],
                               b.getArray()[problem.block_slice(k)].reshape(n, 3)]))
    rows = np.concatenate(comm.allgather(np.concatenate(rows)))
    return rows[np.lexsort(np.round(rows[:, 2::-1].T, 9))]


def test_mortar_residual_does_not_depend_on_the_partition():
    """The mortar weights are integrated on the ranks that hold the slave faces and summed
    on each node's owner: the residual of every node of both bodies on 1, 2 or 3 ranks
    equals the one a single rank computes with the whole meshes (measured: 4.7e-15 on 2
    ranks, 1.1e-14 on 3, of the largest entry; a 1 % error in the integrals sent to
    another rank reads 6e-4)."""
    whole = _mortar_residual_by_node(MPI.COMM_SELF)
    parts = _mortar_residual_by_node(MPI.COMM_WORLD)
    assert np.array_equal(np.round(parts[:, :3], 9), np.round(whole[:, :3], 9))
    scale = np.abs(whole[:, 3:]).max()
    assert scale > 0.0
    print(f"\nworst residual difference {np.abs(parts[:, 3:] - whole[:, 3:]).max() / scale:.1e}")
    assert np.abs(parts[:, 3:] - whole[:, 3:]).max() < 1e-12 * scale


@pytest.mark.parametrize("mu", [0.0, 0.3])
def test_jacobian_mortar_in_3d_matches_central_differences(mu):
    """The mortar distribution in 3D: a hexahedral block (Q4 slave faces) pressed onto a
    tetrahedral foundation (T3 master faces) and slid, its top held and moved."""
    Vb, tb, ub, Fb = box_3d(0.25, 0.3, 0.5, 0.2, 4, mesh.CellType.hexahedron)
    Vf, tf, uf, Ff = box_3d(0.0, 0.0, 1.0, 0.3, 5, mesh.CellType.tetrahedron)
    g = fem.Constant(Vb.mesh, np.zeros(3))
    bcs = [fem.dirichletbc(g, fem.locate_dofs_topological(Vb, 2, tb.find(TOP)), Vb),
           fem.dirichletbc(np.zeros(3), fem.locate_dofs_topological(Vf, 2, tf.find(BOTTOM)),
                           Vf)]
    contact = NodeToSurface(Surface(Vb, tb, BOTTOM), Surface(Vf, tf, TOP), E=E,
                            K=100 * E / 0.125, stick_slope=10 * E / 0.125, mu=mu,
                            distribution="mortar")
    problem = BlockProblem([Fb, Ff], [ub, uf], bcs, [contact])

    def press(t):
        g.value[:] = (0.0, 0.0, -0.01 * t)

    def drag(t):
        g.value[:] = (0.01 * t, 0.005 * t, -0.01)
    solve_steps(problem, press, 1)
    if mu > 0:
        solve_steps(problem, drag, 1)
    err = fd_error(problem, contact)
    print(f"\nhexahedra on tetrahedra, mortar, mu = {mu}: FD rel error {err:.2e}, statuses "
          f"{sorted(statuses(contact))}")
    assert ({1, 2} if mu > 0 else {2}) <= statuses(contact)
    assert err < 1e-7
    assert_sparse_tangent(contact)


def circle_distance(center, radius):
    """The signed distance of a circle, its gradient and Hessian, for :func:`rigid_sdf`."""
    def distance(y):
        return np.linalg.norm(y - center, axis=1) - radius

    def gradient(y):
        v = y - center
        return v / np.linalg.norm(v, axis=1)[:, None]

    def hessian(y):
        v = y - center
        r = np.linalg.norm(v, axis=1)
        n = v / r[:, None]
        return (np.eye(2) - n[:, :, None] * n[:, None, :]) / r[:, None, None]
    return distance, gradient, hessian


def press_and_turn(problem, contact, rotation=0.05):
    def press(t):
        contact.obstacle_translation = (0.0, 0.02 * t)

    def turn(t):
        contact.obstacle_translation = (0.02 * t, 0.02)
        contact.obstacle_rotation = rotation * t
    solve_steps(problem, press, 2)
    solve_steps(problem, turn, 2)


@pytest.mark.parametrize("hessian", ["given", "differences"])
def test_a_signed_distance_circle_is_the_rigid_circle(hessian):
    """An obstacle given by the signed distance of a circle (its gradient the normal) turning
    and sliding under the block: the forces and moment of the analytic circle, and an exact
    tangent (with the Hessian by central differences, to their error)."""
    center = np.array([0.5, -1.0])
    distance, gradient, exact = circle_distance(center, 1.0)
    results = []
    for obstacle in (rigid_sphere(center, 1.0),
                     rigid_sdf(distance, gradient, exact if hessian == "given" else None,
                               reference=center)):
        problem, contact = on_turning_obstacle(2, obstacle)
        press_and_turn(problem, contact)
        results.append((contact.force(), contact.obstacle_moment(), fd_error(problem, contact)))
    (F, M, _), (F_sdf, M_sdf, err) = results
    print(f"\nsigned distance ({hessian} Hessian) vs circle: force {np.abs(F_sdf - F).max():.1e},"
          f" moment {abs(M_sdf - M):.1e}; FD rel error {err:.2e}")
    np.testing.assert_allclose(F_sdf, F, rtol=1e-9, atol=1e-9 * np.abs(F).max())
    assert M_sdf == pytest.approx(M, rel=1e-9)
    assert err < 1e-7


def test_jacobian_on_a_wavy_signed_distance():
    """A wavy rigid floor y = A cos(k x) - 0.02 (its level function, not a true distance)
    turning about a point under the block: the tangent against central differences."""
    A, k = 0.01, 2 * np.pi

    def distance(y):
        return y[:, 1] - A * np.cos(k * y[:, 0])

    def gradient(y):
        return np.stack([A * k * np.sin(k * y[:, 0]), np.ones(len(y))], axis=1)

    def hessian(y):
        H = np.zeros((len(y), 2, 2))
        H[:, 0, 0] = A * k * k * np.cos(k * y[:, 0])
        return H
    problem, contact = on_turning_obstacle(2, rigid_sdf(distance, gradient, hessian,
                                                        reference=[0.5, 0.0]))

    def press(t):
        contact.obstacle_translation = (0.0, 0.012 * t)

    def turn(t):
        contact.obstacle_translation = (0.01 * t, 0.012)
        contact.obstacle_rotation = 0.005 * t
    solve_steps(problem, press, 2)
    solve_steps(problem, turn, 2)
    err = fd_error(problem, contact)
    print(f"\nwavy signed distance: FD rel error {err:.2e}, statuses {sorted(statuses(contact))}")
    assert {1, 2} <= statuses(contact)
    assert err < 1e-7


def test_an_obstacle_without_reference_does_not_turn():
    distance, gradient, hessian = circle_distance(np.array([0.5, -1.0]), 1.0)
    _, contact = on_turning_obstacle(2, rigid_sdf(distance, gradient, hessian))
    with pytest.raises(ContactSetupError) as caught:
        contact.obstacle_rotation = 0.1
    assert "obstacle rotation" in str(caught.value) and "reference" in str(caught.value)
    assert "\n" not in str(caught.value)
    _, contact = on_turning_obstacle(3, rigid_sphere([0.5, 0.5, -1.0], 1.0))
    for bad, words in ((0.1, "rotation vector of 3 numbers in 3D"),
                       ([0.0, np.nan, 0.0], "finite")):
        with pytest.raises(ContactSetupError, match=words):
            contact.obstacle_rotation = bad


def test_newton_converges_quadratically():
    """One large increment (press deeper and slide, with friction) to a tight tolerance:
    the order of the last iterations above the round-off floor (every step with a new
    Jacobian: no chord steps)."""
    problem, contact = on_plane()
    press_and_slide(problem, contact, slide=0.0, increments=(2, 1))
    contact.obstacle_translation = (0.02, 0.05)
    contact.begin(problem.x)
    result = Newton(rtol=1e-15, atol=0.0, chord=0.0).solve(problem)
    r = np.array(result.residuals)
    above_floor = [k for k in range(1, len(r) - 1) if r[k + 1] > 100 * r[-1]]
    k = above_floor[-1]
    order = np.log(r[k + 1] / r[k]) / np.log(r[k] / r[k - 1])
    print(f"\nresiduals {np.array2string(r, precision=1)}: order {order:.2f}, "
          f"statuses {sorted(statuses(contact))}")
    assert result.converged and statuses(contact) & {1, 2}  # closed, with friction
    assert order >= 1.8


def test_update_at_the_same_iterate_keeps_its_evaluation():
    """An update that pairs the same elements at the iterate last evaluated keeps that
    evaluation (Newton then keeps the residual too); a new iterate, or a new increment,
    is evaluated, and the kept evaluation is the one a fresh update would give."""
    problem, contact = on_plane()
    press_and_slide(problem, contact, slide=0.01, increments=(2, 1))
    contact.begin(problem.x)
    contact.update(problem.x)
    first, force = contact.evaluations, contact.force()
    contact.update(problem.x, pairing=False)
    contact.update(problem.x)
    assert contact.evaluations == first and np.array_equal(contact.force(), force)
    problem.x.shift(1e-9)
    contact.update(problem.x)
    assert contact.evaluations == first + 1
    problem.x.shift(-1e-9)
    contact.begin(problem.x)  # a new increment: evaluated anew, to the same forces
    contact.update(problem.x)
    assert contact.evaluations == first + 2
    np.testing.assert_allclose(contact.force(), force, rtol=1e-12, atol=0.0)


def lifted(problem, dy: float) -> PETSc.Vec:
    """A copy of the problem's vector with the block moved up by ``dy``."""
    x = problem.x.copy()
    s = problem.block_slice(0)
    x.getArray()[s.start + 1:s.stop:2] += dy
    return x


def test_an_equilibrium_of_frozen_pairings_is_not_an_answer():
    """Pairing froze (``pairing_iterations`` = 2) with the block lifted off the plane;
    then the iterate sinks the block 0.01 into the plane: its frozen pairing has no
    element, a pairing at that iterate closes all 9 bottom nodes.  ``stale_pairing``
    counts them and the postcondition rejects the state whatever its residual.  Paired
    at that iterate, or frozen where pairing there changes nothing: 0."""
    problem, contact = on_plane(mu=0.0, pairing_iterations=2)
    up, down = lifted(problem, 0.05), lifted(problem, -0.01)
    contact.begin(up)
    for _ in range(3):
        contact.update(up)
    contact.update(down)
    assert contact.stale_pairing() == 9
    b = problem.x.duplicate()
    problem.residual(down, b)
    assert "pairing at the converged state closes or opens 9" in problem.postcondition(1e30)
    for frozen in (False, True):
        contact.begin(down)
        for _ in range(4 if frozen else 1):
            contact.update(down)
        assert contact.stale_pairing() == 0
        assert 0 not in statuses(contact)  # all closed


def test_a_node_its_multiplier_holds_closed_keeps_its_element():
    """``method="augmented"``: after a converged press the next increment's first pairing,
    at an iterate that lifts the block 6e-4 (beyond the cutoff, within the clearance the
    multipliers close: measured, 8e-4 opens the end nodes), keeps every bottom node's
    element, closed; the cutoff alone dropped all 9 with their multipliers."""
    V, tags = block(0.0, 0.0, 1.0, 0.5, 8, 4)
    u = fem.Function(V)
    held = fem.dirichletbc(np.zeros(2), fem.locate_dofs_topological(V, 1, tags.find(TOP)), V)
    contact = NodeToSurface(Surface(V, tags, BOTTOM), rigid_plane([0, 0], [0, 1]), E=E,
                            mu=0.0, method="augmented")
    problem = BlockProblem([neo_hookean(u, ufl.TestFunction(V))], [u], [held], [contact])
    solve_steps(problem, lambda t: setattr(contact, "obstacle_translation", (0.0, 0.03 * t)),
                2)
    x = lifted(problem, 6e-4)
    contact.begin(x)
    contact.update(x)
    status = np.concatenate(MPI.COMM_WORLD.allgather(contact.state().status))
    assert len(status) == 9 and np.all(status > 0)


def test_snes_matches_newton():
    answers = []
    for use_snes in (False, True):
        problem, contact = on_plane()
        press_and_slide(problem, contact, slide=0.01, increments=(2, 1))
        contact.obstacle_translation = (0.02, 0.03)
        problem.apply_bcs()
        contact.begin(problem.x)
        if use_snes:
            snes = snes_solve(problem, options={"snes_rtol": 1e-12, "snes_atol": 1e-12})
            assert snes.getConvergedReason() > 0 and snes.getIterationNumber() >= 1
            norms = snes.getConvergenceHistory()[0][: snes.getIterationNumber() + 1]
            assert norms[-1] < 1e-6 * norms[0]  # the residual history is the SNES's own
            snes.destroy()
        else:
            assert Newton(rtol=1e-12, atol=1e-12).solve(problem).converged
        answers.append(contact.force())
    print(f"\nforce Newton {answers[0]}, SNES {answers[1]}")
    assert np.allclose(answers[0], answers[1], rtol=1e-9, atol=0.0)


#: a frictional slide: the rigid plane rises in 2 increments, then slides in 4 (stick, partial
#: slip, full slip); obstacle translation per increment
SLIDE = [(0.0, 0.015), (0.0, 0.03)] + [(0.02 * k, 0.03) for k in (1, 2, 3, 4)]


def own_newton_loop(loads) -> list[np.ndarray]:
    """The loop of the module docstring of dolfinx_friction.fem.node_to_surface, written by hand with
    dolfinx's own assemblers on u.vector (Newton with a halving line search, begun at the
    converged state): the contact force and displacement after each increment."""
    V, tags = block(0.0, 0.0, 1.0, 0.5, 8, 4)
    u, v = fem.Function(V), ufl.TestFunction(V)
    held = fem.dirichletbc(np.zeros(2), fem.locate_dofs_topological(V, 1, tags.find(TOP)), V)
    contact = NodeToSurface(Surface(V, tags, BOTTOM), rigid_plane([0, 0], [0, 1]), E=E,
                            K=100 * E / 0.125, stick_slope=10 * E / 0.125, mu=0.3)
    R = neo_hookean(u, v)
    F, J = compat.form(R), compat.form(ufl.derivative(R, u))
    x = compat.petsc_vector(u)
    b, dx = x.duplicate(), x.duplicate()
    ksp = PETSc.KSP().create(MPI.COMM_WORLD)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")

    def residual(pairing=True) -> float:
        if contact.update(x, pairing=pairing):
            raise AssertionError("a new search: make the matrix again")
        compat.assemble_residual_into(b, F, J, [held], x)
        contact.add_residual(b, [held])
        return b.norm()

    answers = []
    for load in loads:
        contact.obstacle_translation = load
        contact.begin(x)
        A = create_matrix(J, [contact])
        norms = [residual()]
        while norms[-1] > 1e-10 and not (norms[-1] < 1e-8 and norms[-1] > 0.1 * norms[-2]):
            A.zeroEntries()
            compat.assemble_matrix_into(A, J, [held])
            contact.add_jacobian(A, [held])
            ksp.setOperators(A)
            ksp.solve(b, dx)
            step = 1.0
            for _ in range(6):  # halve the step while the residual does not decrease
                x.axpy(-step, dx)
                x.ghostUpdate(PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)
                if residual(pairing=False) < norms[-1]:
                    break
                x.axpy(step, dx)
                step /= 2
            norms.append(residual())
            assert len(norms) < 40, norms
        answers.append(np.concatenate([contact.force(), x.getArray()]))
        contact.commit()
    # the matrix of the form alone has no room for the couplings: one clear error
    plain = compat.create_matrix(J)
    compat.assemble_matrix_into(plain, J, [held])
    with pytest.raises(ContactSetupError, match="no slots for the current contact couplings"):
        contact.add_jacobian(plain, [held])
    return answers


def test_increments_do_not_depend_on_their_first_iterate():
    """A frictional slide by solve_steps (which starts each increment from a predictor), by
    a loop around snes_solve and by a hand-written Newton loop (both begun at the converged
    state): the same contact force and displacements after every increment, to 1e-9.
    (The slave areas were measured at the first iterate: 1e-5 apart in the slide.)"""
    problem, contact = on_plane()
    stepped = []

    def record(_increment):
        stepped.append(np.concatenate([contact.force(), problem.x.getArray()]))
    newton = Newton(rtol=1e-13, atol=1e-13)
    solve_steps(problem, lambda t: setattr(contact, "obstacle_translation", (0.0, 0.03 * t)),
                2, newton, on_increment=record)
    solve_steps(problem, lambda t: setattr(contact, "obstacle_translation", (0.08 * t, 0.03)),
                4, newton, on_increment=record)

    problem, contact = on_plane()
    snes = []
    for load in SLIDE:
        contact.obstacle_translation = load
        problem.apply_bcs()
        contact.begin(problem.x)
        assert snes_solve(problem, options={"snes_rtol": 1e-14,
                                            "snes_atol": 1e-13}).getConvergedReason() > 0
        snes.append(np.concatenate([contact.force(), problem.x.getArray()]))
        contact.commit()

    own = own_newton_loop(SLIDE)
    ratio = stepped[-1][0] / stepped[-1][1]
    worst = []
    for a, b, c in zip(stepped, snes, own):
        scale = [np.abs(c[:2]).max(),
                 MPI.COMM_WORLD.allreduce(np.abs(c[2:]).max(initial=0.0), op=MPI.MAX)]
        local = max(max(np.abs(p[:2] - q[:2]).max() / scale[0],
                        np.abs(p[2:] - q[2:]).max(initial=0.0) / scale[1])
                    for p, q in ((a, b), (a, c), (b, c)))
        worst.append(MPI.COMM_WORLD.allreduce(local, op=MPI.MAX))
    print(f"\nF_t/F_n at the end {ratio:.6f}; per increment, the largest relative difference "
          f"among the three: {' '.join(f'{w:.1e}' for w in worst)}")
    assert abs(ratio - 0.3) < 1e-9  # the slide reaches full slip
    assert len(worst) == len(SLIDE) and max(worst) < 1e-9


def resting(cell=mesh.CellType.quadrilateral, mu=0.0, spring=0.0):
    """A block whose top is pressed down 0.01 onto a rigid plane and held only normally
    (2D: y; 3D: z): with mu = 0 and no ``spring`` (a foundation of that stiffness per area
    on its whole boundary, in the plane's directions) nothing holds its motions along the
    plane.  Returns the problem, its contact and the load function."""
    if cell == mesh.CellType.hexahedron:
        m = mesh.create_box(MPI.COMM_WORLD, [[0, 0, 0], [1, 1, 0.5]], [2, 2, 1], cell)
        facets = [mesh.locate_entities_boundary(m, 2, lambda x, z=z: np.isclose(x[2], z))
                  for z in (0.0, 0.5)]
        V = compat.vector_space(m, 1)
        tags = mesh.meshtags(m, 2, *(np.concatenate(a)[np.argsort(np.concatenate(facets))]
                                     for a in (facets, [np.full(len(f), t, np.int32) for f, t
                                                        in zip(facets, (BOTTOM, TOP))])))
    else:
        V, tags = block(0.0, 0.0, 1.0, 0.5, 4, 2, cell)
    d = V.mesh.geometry.dim
    u, v = fem.Function(V), ufl.TestFunction(V)
    lam, G = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    eps = ufl.sym(ufl.grad(u))
    F = ufl.inner(2 * G * eps + lam * ufl.tr(eps) * ufl.Identity(d), ufl.grad(v)) * ufl.dx
    if spring:
        F += spring * sum(u[i] * v[i] for i in range(d - 1)) * ufl.ds
    g = compat.scalar_constant(V.mesh, 0.0)
    held = fem.dirichletbc(g, fem.locate_dofs_topological(V.sub(d - 1), d - 1, tags.find(TOP)),
                           V.sub(d - 1))
    plane = rigid_plane(np.zeros(d), np.eye(d)[-1])
    contact = NodeToSurface(Surface(V, tags, BOTTOM), plane, E=E, mu=mu, K=1e5,
                            stick_slope=1e4)
    problem = BlockProblem([F], [u], [held], [contact])

    def press(t):
        g.value = -0.01 * t
    return problem, contact, press


def test_a_rigid_motion_that_nothing_holds_is_refused():
    """A block on a frictionless rigid plane, held only normally at its top, converged to an
    arbitrary sideways drift (the Jacobian is singular along the plane, the residual does
    not see the drift): solve_steps, snes_solve and Newton now stop at the first converged
    state with one line naming the body and the motion.  With friction, or a spring along
    the plane, nothing is said."""
    problem, contact, press = resting()
    with pytest.raises(ContactSetupError) as info:
        solve_steps(problem, press, 2)
    message = str(info.value)
    assert message.startswith("body 0 can move rigidly (translation along (1, 0)) with nothing "
                              "to hold it") and "\n" not in message, message
    problem, contact, press = resting()
    press(1.0)
    problem.apply_bcs()
    contact.begin(problem.x)
    with pytest.raises(ContactSetupError, match=r"translation along \(1, 0\)"):
        snes_solve(problem)
    for kind in ({"mu": 0.3}, {"spring": 1e-3 * E}):
        problem, contact, press = resting(**kind)
        solve_steps(problem, press, 2)
        assert statuses(contact) <= {1, 2}  # closed everywhere


def test_free_motions_in_3d_are_named():
    """3D: a box on a frictionless plane, held only in z at its top, is free along x and y
    and about z; the line names one motion and counts the others."""
    problem, contact, press = resting(mesh.CellType.hexahedron)
    press(1.0)
    problem.apply_bcs()
    contact.begin(problem.x)
    with pytest.raises(ContactSetupError) as info:
        Newton().solve(problem)
    message = str(info.value)
    assert "body 0 can move rigidly (translation along (" in message, message
    assert "; 2 more such motions)" in message and "\n" not in message, message


@pytest.mark.parametrize("d, expected", [
    (2, "body 'block' can move rigidly (rotation about (0.75, 0.5)) with nothing to hold it"),
    (3, "body 'block' can move rigidly (rotation about the axis (0, 0, 1) through "
        "(0.5, 0.5, 0.25)) with nothing to hold it")])
def test_a_free_rotation_is_named_with_its_axis(d, expected):
    """A body held only at the nodes on a line (2D: a point) can turn about it; the body is
    named as given to BlockProblem."""
    if d == 2:
        V, _ = block(0.0, 0.0, 1.0, 0.5, 4, 2)
        pinned = lambda x: np.isclose(x[0], 0.75) & np.isclose(x[1], 0.5)  # noqa: E731
    else:
        V = compat.vector_space(mesh.create_box(MPI.COMM_WORLD, [[0, 0, 0], [1, 1, 0.5]],
                                                [2, 2, 1], mesh.CellType.hexahedron), 1)
        pinned = lambda x: np.isclose(x[0], 0.5) & np.isclose(x[1], 0.5)  # noqa: E731
    u, v = fem.Function(V), ufl.TestFunction(V)
    eps = ufl.sym(ufl.grad(u))
    F = ufl.inner(E * eps + E * ufl.tr(eps) * ufl.Identity(d), ufl.grad(v)) * ufl.dx
    held = fem.dirichletbc(np.zeros(d), fem.locate_dofs_geometrical(V, pinned), V)
    problem = BlockProblem([F], [u], [held], names=["block"])
    with pytest.raises(ContactSetupError) as info:
        Newton().solve(problem)
    assert str(info.value).startswith(expected), str(info.value)


def test_bad_input_gets_one_clear_line():
    V, tags = block(0.0, 0.0, 1.0, 0.5, 4, 2)
    W, other = block(0.0, 0.6, 1.0, 0.5, 2, 1)  # another mesh: its facet numbers fit V's too
    plane = rigid_plane([0, 0], [0, 1])
    cases = [
        (lambda: NodeToSurface(Surface(V, other, BOTTOM), plane, E=E),
         "slave: the tags of facets tagged 1 were made on another mesh"),
        (lambda: NodeToSurface(Surface(W, other, BOTTOM), Surface(V, other, TOP),
                               spaces=[W, V], E=E),
         "master: the tags of facets tagged 2 were made on another mesh"),
        (lambda: NodeToSurface(Surface(V, tags, 7), plane, E=E), "no facet is tagged 7"),
        (lambda: NodeToSurface(Surface(compat.scalar_space(V.mesh, 1), tags, BOTTOM), plane,
                               E=E), "vector space"),
        (lambda: NodeToSurface(Surface(V, tags, BOTTOM), Surface(V, tags, BOTTOM), E=E),
         "share facets"),
        (lambda: rigid_plane([0, 0], [0, 0]), "normal is zero"),
        (lambda: rigid_plane([0, np.nan], [0, 1]), "finite"),
        (lambda: NodeToSurface(Surface(V, tags, BOTTOM), plane, E=E, mu=-0.3),
         "mu = -0.3: must be >= 0"),
        (lambda: NodeToSurface(Surface(V, tags, BOTTOM), plane, mu=0.3), "give E"),
        (lambda: NodeToSurface(Surface(V, tags, BOTTOM), rigid_plane([0, 0, 0], [0, 0, 1]),
                               E=E), "3 components"),
        (lambda: NodeToSurface(Surface(V, tags, BOTTOM), plane, E=E, K="ccx"),
         'K = "ccx": must be a number > 0 or "calculix"'),
        (lambda: NodeToSurface(Surface(V, tags, BOTTOM), plane, E=E, mu=0.3,
                               stick_slope="stiff"),
         'stick_slope = "stiff": must be a number > 0 or "calculix"'),
        (lambda: NodeToSurface(Surface(V, tags, BOTTOM), plane, mu=0.3, K=1e4,
                               stick_slope="calculix"), "give E"),
        (lambda: NodeToSurface(Surface(V, tags, BOTTOM), plane, E=1e307), "is so large"),
        (lambda: NodeToSurface(Surface(V, tags, BOTTOM), plane, E=E, distribution="segment"),
         'distribution = "segment": must be one of "nodal", "mortar"'),
    ]
    assert rigid_plane([0, 0], [0, 1e-200]).normal == (0.0, 1.0)  # tiny, not zero
    for make, text in cases:
        with pytest.raises(ContactSetupError) as info:
            make()
        message = str(info.value)
        assert text in message and "\n" not in message, message


@pytest.mark.parametrize("cell", [mesh.CellType.quadrilateral, mesh.CellType.triangle])
def test_default_penalty_scales_with_the_slave_node_spacing(cell):
    """K = 10 E/h and lambda = E/h with h the median slave node spacing (the element size of
    a uniform mesh, on every rank the same); "calculix": 50 E and E/2; numbers as given."""
    plane = rigid_plane([0, 0], [0, 1])
    V, tags = block(0.0, 0.0, 1.0, 0.5, 8, 2, cell)  # bottom: 8 faces of length 1/8
    contact = NodeToSurface(Surface(V, tags, BOTTOM), plane, E=E, mu=0.3)
    h = contact.spacing
    assert h == pytest.approx(1 / 8, rel=1e-12)
    assert MPI.COMM_WORLD.allgather(h) == [h] * MPI.COMM_WORLD.size
    assert contact.law.K == pytest.approx(10 * E / h, rel=1e-12)
    assert contact.stick_slope == pytest.approx(E / h, rel=1e-12)
    resolved = contact.resolved()
    assert resolved == {"law": "linear", "K": contact.law.K, "sigma_inf": E / 70000,
                        "c0": 1e-3, "mu": 0.3, "stick_slope": contact.stick_slope,
                        "tangent": "consistent", "pairing_iterations": 8,
                        "method": "penalty", "augmented_tolerance": 1e-4,
                        "distribution": "nodal", "spacing": h}
    calculix = NodeToSurface(Surface(V, tags, BOTTOM), plane, E=E, mu=0.3, K="calculix",
                             stick_slope="calculix")
    assert (calculix.law.K, calculix.stick_slope) == (50 * E, E / 2)
    given = NodeToSurface(Surface(V, tags, BOTTOM), plane, E=E, mu=0.3, K=123.0,
                          stick_slope=4.5)
    assert (given.law.K, given.stick_slope) == (123.0, 4.5)
    finer, ftags = block(0.0, 0.0, 1.0, 0.5, 16, 2, cell)
    halved = NodeToSurface(Surface(finer, ftags, BOTTOM), plane, E=E, mu=0.3)
    assert halved.law.K == pytest.approx(2 * contact.law.K, rel=1e-12)


def test_fields_are_the_state_on_the_slave_mesh():
    """contact.fields(): the nodal fields' names and status codes as dolfinx Functions; at
    every slave node with an element they hold the state's values, elsewhere 0 and -1
    (P2: midside nodes included)."""
    problem, contact = on_plane(degree=2, cell=mesh.CellType.triangle)
    press_and_slide(problem, contact, increments=(2, 1))
    fields = contact.fields()
    assert sorted(fields) == ["contact_pressure", "slip", "status", "tangential_traction"]
    st = contact.state()
    s = st.has_element
    assert s.any() or MPI.COMM_WORLD.size > 1
    status = fields["status"].x.array
    np.testing.assert_array_equal(status[st.nodes[s]], st.status[s])
    np.testing.assert_array_equal(fields["contact_pressure"].x.array[st.nodes[s]], st.pressure[s])
    np.testing.assert_array_equal(fields["slip"].x.array[st.nodes[s]], st.slip[s])
    traction = fields["tangential_traction"].x.array.reshape(-1, 2)
    np.testing.assert_array_equal(traction[st.nodes[s]], st.traction[s])
    owned = fields["status"].function_space.dofmap.index_map.size_local  # ghosts: owners' values
    away = np.setdiff1d(np.arange(owned), st.nodes)
    assert np.all(status[away] == NO_ELEMENT) and not fields["contact_pressure"].x.array[away].any()
    assert 2 in statuses(contact)  # the slide reached slip: every status code was written


def test_reference_pressure_is_per_undeformed_area():
    """ContactState.reference_area: the slave nodes' areas on the undeformed faces (they sum
    to the block's width, 1, whatever the deformation); reference_pressure times it is the
    normal force, as pressure times the deformed area is."""
    problem, contact = on_plane()
    press_and_slide(problem, contact, increments=(2, 1))
    st = contact.state()
    total = MPI.COMM_WORLD.allreduce(st.reference_area.sum())
    assert abs(total - 1.0) < 1e-12
    s = st.has_element
    np.testing.assert_allclose(st.reference_pressure[s] * st.reference_area[s],
                               st.normal_force[s], rtol=1e-12, atol=0.0)
    np.testing.assert_allclose(st.pressure[s] * st.area[s], st.normal_force[s], rtol=1e-12,
                               atol=0.0)
    deformed = MPI.COMM_WORLD.allreduce(st.area.sum())
    assert abs(deformed - 1.0) > 1e-6  # finite strain: the deformed areas differ


def test_reaction_of_a_dirichlet_condition_in_one_call():
    """BlockProblem.reaction(bc or facet group): a block pressed onto a foundation and slid;
    the reactions at the block's top and the foundation's bottom balance, the top's is
    minus the contact force on the block, and so is the force on the foundation's contact
    face (each dof counted once: 1, 2 and 3 ranks alike)."""
    Vb, tb = block(0.2, 0.4, 0.6, 0.3, 6, 3)
    Vf, tf = block(0.0, 0.0, 1.0, 0.4, 9, 4, mesh.CellType.triangle)
    ub, uf = fem.Function(Vb), fem.Function(Vf)
    g = fem.Constant(Vb.mesh, np.zeros(2))
    top = fem.dirichletbc(g, fem.locate_dofs_topological(Vb, 1, tb.find(TOP)), Vb)
    bottom = fem.dirichletbc(np.zeros(2), fem.locate_dofs_topological(Vf, 1, tf.find(BOTTOM)),
                             Vf)
    contact = NodeToSurface(Surface(Vb, tb, BOTTOM), Surface(Vf, tf, TOP), E=E,
                            K=100 * E / 0.1, stick_slope=10 * E / 0.1, mu=0.3)
    problem = BlockProblem([neo_hookean(ub, ufl.TestFunction(Vb)),
                            neo_hookean(uf, ufl.TestFunction(Vf))], [ub, uf], [top, bottom],
                           [contact])
    press_and_slide(problem, contact, g)
    R_top, R_bottom = problem.reaction(top), problem.reaction(bottom)
    scale = np.abs(R_top).max()
    assert scale > 1.0 and abs(R_top[0]) > 0.1 * scale  # pressed and dragged
    np.testing.assert_allclose(R_top, -R_bottom, rtol=0.0, atol=1e-8 * scale)
    np.testing.assert_allclose(R_top, -contact.force(), rtol=0.0, atol=1e-8 * scale)
    # facet groups: the held top's facets as its condition; two parts of them that share
    # no node (the facets from x = 0.2 to 0.3 and from 0.4 to 0.8) sum to it; the free
    # contact face of the foundation is held by nothing
    np.testing.assert_allclose(problem.reaction(Surface(Vb, tb, TOP)), R_top, rtol=0.0,
                               atol=1e-12 * scale)
    held = tb.find(TOP)
    x = mesh.compute_midpoints(Vb.mesh, 1, held)[:, 0]
    parts = mesh.meshtags(Vb.mesh, 1, held, np.where(x < 0.3, 3, np.where(x > 0.4, 4, 5))
                          .astype(np.int32))
    R_left, R_right = (problem.reaction(Surface(Vb, parts, v)) for v in (3, 4))
    assert min(np.abs(R_left).max(), np.abs(R_right).max()) > 0.01 * scale
    np.testing.assert_allclose(R_left + R_right, R_top, rtol=0.0, atol=1e-12 * scale)
    np.testing.assert_allclose(problem.reaction(Surface(Vf, tf, TOP)), 0.0, rtol=0.0,
                               atol=1e-8 * scale)
    with pytest.raises(ContactSetupError, match="reaction: the facet group is on none"):
        problem.reaction(Surface(compat.vector_space(Vb.mesh, 1), tb, TOP))
    other = fem.dirichletbc(np.zeros(2), fem.locate_dofs_topological(Vb, 1, tb.find(TOP)),
                            compat.vector_space(Vb.mesh, 1))
    with pytest.raises(ContactSetupError, match="reaction: the condition is on none"):
        problem.reaction(other)


def test_solve_steps_drives_snes_to_newtons_answer():
    """solve_steps(..., newton=SNESNewton(...)): the same press and slide as with the
    package's Newton, every increment's contact force to 1e-8; the increments carry the
    residual norms SNES recorded."""
    forces = []
    for newton in (Newton(rtol=1e-12, atol=1e-11),
                   SNESNewton(options={"snes_rtol": 1e-12, "snes_atol": 1e-11})):
        problem, contact = on_plane()
        seen = []
        solve_steps(problem, lambda t: setattr(contact, "obstacle_translation", (0.0, 0.03 * t)),
                    2, newton=newton, on_increment=lambda inc: seen.append(contact.force()))
        records = solve_steps(problem, lambda t: setattr(contact, "obstacle_translation",
                                                         (0.02 * t, 0.03)), 2, newton=newton,
                              on_increment=lambda inc: seen.append(contact.force()))
        assert all(r.residuals[-1] <= r.tolerance for r in records)
        forces.append(np.array(seen))
    assert forces[0].shape == forces[1].shape
    np.testing.assert_allclose(forces[1], forces[0], rtol=0.0, atol=1e-8 * np.abs(forces[0]).max())
