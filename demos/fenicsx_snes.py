"""Contact in dolfinx's own SNES idiom: a Neo-Hookean block written as a dolfinx 0.10+
``NonlinearProblem``, pressed onto a rigid plane and dragged over it (mu = 0.3).

    python3 demos/fenicsx_snes.py            # serially
    mpirun -n 2 python3 demos/fenicsx_snes.py

The script is a plain dolfinx program (mesh, space, UFL residual, Dirichlet condition,
``NonlinearProblem`` with its PETSc options); dolfinx_friction adds the contact pair to
that problem (``add_contact``): its forces and exact tangent in the SNES callbacks, the
couplings in the matrix, the search per increment, and the friction history committed
with each converged increment, together with the script's own history (here a log of
the converged contact forces).  Once every contact node slips, drag / press = mu.
It needs dolfinx >= 0.10; on older releases it says so and stops.
"""
import inspect
import sys

import dolfinx
import numpy as np
import ufl
from dolfinx import fem, mesh
from dolfinx.fem.petsc import NonlinearProblem
from mpi4py import MPI

from dolfinx_friction import NodeToSurface, Surface, add_contact, rigid_plane

if "petsc_options_prefix" not in inspect.signature(NonlinearProblem).parameters:
    print(f"demos/fenicsx_snes.py needs dolfinx >= 0.10 (its SNES NonlinearProblem); this is "
          f"dolfinx {dolfinx.__version__}: see demos/fenicsx_neo_hookean.py")
    sys.exit(0)

comm = MPI.COMM_WORLD
BOTTOM, TOP = 1, 2

# The block (1 x 0.5, plane strain) with its bottom and top edges tagged
domain = mesh.create_rectangle(comm, [[0.0, 0.0], [1.0, 0.5]], [20, 10],
                               mesh.CellType.quadrilateral)
facets, values = [], []
for y, tag in ((0.0, BOTTOM), (0.5, TOP)):
    found = mesh.locate_entities_boundary(domain, 1, lambda x, y=y: np.isclose(x[1], y))
    facets.append(found)
    values.append(np.full(len(found), tag, dtype=np.int32))
order = np.argsort(np.concatenate(facets))
tags = mesh.meshtags(domain, 1, np.concatenate(facets)[order], np.concatenate(values)[order])

# Compressible Neo-Hookean (CalculiX's NEO HOOKE), plane strain
E, nu = 1000.0, 0.3
mu_s, kappa = E / (2 * (1 + nu)), E / (3 * (1 - 2 * nu))
V = fem.functionspace(domain, ("Lagrange", 1, (2,)))
u, v = fem.Function(V, name="displacement"), ufl.TestFunction(V)
F2 = ufl.variable(ufl.Identity(2) + ufl.grad(u))
F3 = ufl.as_matrix([[F2[0, 0], F2[0, 1], 0], [F2[1, 0], F2[1, 1], 0], [0, 0, 1]])
J = ufl.det(F3)
W = mu_s / 2 * (J ** (-2 / 3) * ufl.tr(F3.T * F3) - 3) + kappa / 2 * (J - 1) ** 2
F = ufl.inner(ufl.diff(W, F2), ufl.grad(v)) * ufl.dx
held = fem.dirichletbc(np.zeros(2), fem.locate_dofs_topological(V, 1, tags.find(TOP)), V)

problem = NonlinearProblem(
    F, u, bcs=[held], petsc_options_prefix="demo_snes_",
    petsc_options={"snes_type": "newtonls", "snes_linesearch_type": "bt",
                   "snes_rtol": 1e-10, "snes_atol": 1e-9, "snes_max_it": 50,
                   "ksp_type": "preonly", "pc_type": "lu",
                   "pc_factor_mat_solver_type": "mumps"})

# The contact: the block's bottom on a rigid plane that rises, then slides
h = 1.0 / 20
pair = NodeToSurface(Surface(V, tags, BOTTOM), rigid_plane([0.0, 0.0], [0.0, 1.0]),
                     E=E, K=100 * E / h, stick_slope=10 * E / h, mu=0.3)


class ForceLog:
    """The script's own history: the contact force of each converged increment."""

    def __init__(self):
        self.forces: list[np.ndarray] = []

    def commit(self):
        self.forces.append(pair.force())

    def rollback(self):
        pass  # nothing was logged for a failed increment


log = ForceLog()
contact = add_contact(problem, [pair], bcs=[held], history=[log])

steps = [("press", (0.0, 0.05 * t)) for t in np.linspace(0.2, 1.0, 5)]
steps += [("slide", (0.3 * t, 0.05)) for t in np.linspace(0.1, 1.0, 10)]
for name, translation in steps:
    pair.obstacle_translation = translation
    reason = contact.solve()
    if reason <= 0:
        raise RuntimeError(f"SNES did not converge ({reason}) at {name} {translation}")
    fx, fy = log.forces[-1]
    closed, slipping = pair.counts()
    if comm.rank == 0:
        print(f"{name} {translation[0]:.3f} {translation[1]:.3f}  "
              f"SNES {contact.snes.getIterationNumber()}  F_n = {fy:.10g}  F_t = {fx:.10g}  "
              f"F_t/F_n = {fx / fy:.10f}  contact {closed}, slip {slipping}")
