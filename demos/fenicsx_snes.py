# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: light
#       format_version: '1.5'
# ---

# # Frictional contact in dolfinx's own SNES idiom
#
# This demo is part of dolfinx_friction. It needs dolfinx 0.10 or later
# (where {py:class}`NonlinearProblem <dolfinx.fem.petsc.NonlinearProblem>`
# is solved by PETSc SNES); on older releases it says so and stops.
# Run it serially or in parallel:
#
# ```bash
# python3 demos/fenicsx_snes.py
# mpirun -n 2 python3 demos/fenicsx_snes.py
# ```
#
# This demo illustrates how to:
#
# - Add node-to-surface penalty contact with Coulomb friction to a
#   `NonlinearProblem` you built yourself, with `add_contact`: the
#   contact's forces and exact tangent join the problem's SNES
#   callbacks, its couplings the problem's matrix.
# - Solve load increments with the problem's own SNES, the contact
#   searched once per increment and its friction history committed with
#   each converged increment.
# - Keep your own history (here a log of the converged increments; a
#   plasticity model's quadrature-point state the same way) committed
#   and rolled back together with the contact's, so that a failed
#   increment can be cut back and retried from a consistent state.
#
# ## Problem definition
#
# A compressible Neo-Hookean block $[0, 1] \times [0, 0.5]$ (plane
# strain, $E = 1000$, $\nu = 0.3$) is held at its top edge. A rigid plane
# under it first rises by $0.05$, pressing the block's bottom edge, and
# then slides by $0.3$ along $x_0$, dragging the block by friction
# (Coulomb, $\mu = 0.3$). Once every contact node slips, the drag over
# the press force is $\mu$.
#
# The block's residual is dolfinx's usual one,
#
# $$
# F(u; v) = \int_\Omega P(u) : \nabla v \, {\rm d}x = 0
# \quad \forall v,
# $$
#
# with $P = \partial W / \partial F$ the first Piola-Kirchhoff stress of
# CalculiX's NEO HOOKE energy $W$. The contact adds to the residual, at
# each node of the bottom edge (the slave nodes), the force of a penalty
# spring against the plane: a normal force $K g \, a$ for an overclosure
# $g$ on the node's area $a$, and a tangential force limited by $\mu$
# times the normal force, elastic (stick, slope $k_t$) below that limit.
# The stick/slip state at the last converged increment is the contact's
# history.
#
# ## Implementation

# +
import inspect
import sys

import dolfinx
import numpy as np
import ufl
from dolfinx import fem, mesh
from dolfinx.fem.petsc import NonlinearProblem
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx_friction import NodeToSurface, Surface, add_contact, rigid_plane

if "petsc_options_prefix" not in inspect.signature(NonlinearProblem).parameters:
    print(f"demos/fenicsx_snes.py needs dolfinx >= 0.10 (its SNES NonlinearProblem); this is "
          f"dolfinx {dolfinx.__version__}: see demos/fenicsx_neo_hookean.py")
    sys.exit(0)
# -

# The block, with its bottom edge (the contact surface) and its top edge
# (held) tagged.

# +
comm = MPI.COMM_WORLD
BOTTOM, TOP = 1, 2
msh = mesh.create_rectangle(comm, [np.array([0.0, 0.0]), np.array([1.0, 0.5])], [20, 10],
                            mesh.CellType.quadrilateral)
fdim = msh.topology.dim - 1
facets, values = [], []
for y, tag in ((0.0, BOTTOM), (0.5, TOP)):
    found = mesh.locate_entities_boundary(msh, fdim, lambda x, y=y: np.isclose(x[1], y))
    facets.append(found)
    values.append(np.full(len(found), tag, dtype=np.int32))
order = np.argsort(np.concatenate(facets))
facet_tags = mesh.meshtags(msh, fdim, np.concatenate(facets)[order],
                           np.concatenate(values)[order])
# -

# The displacement space, the Neo-Hookean residual (plane strain: the
# deformation gradient embedded in 3D) and the held top edge.

# +
E, nu = 1000.0, 0.3
mu_s, kappa = E / (2 * (1 + nu)), E / (3 * (1 - 2 * nu))
V = fem.functionspace(msh, ("Lagrange", 1, (2,)))
u = fem.Function(V, name="displacement")
v = ufl.TestFunction(V)
F2 = ufl.variable(ufl.Identity(2) + ufl.grad(u))
F3 = ufl.as_matrix([[F2[0, 0], F2[0, 1], 0], [F2[1, 0], F2[1, 1], 0], [0, 0, 1]])
J = ufl.det(F3)
W = mu_s / 2 * (J ** (-2 / 3) * ufl.tr(F3.T * F3) - 3) + kappa / 2 * (J - 1) ** 2
F = ufl.inner(ufl.diff(W, F2), ufl.grad(v)) * ufl.dx
held = fem.dirichletbc(np.zeros(2, dtype=dolfinx.default_scalar_type),
                       fem.locate_dofs_topological(V, fdim, facet_tags.find(TOP)), V)
# -

# The `NonlinearProblem` as any dolfinx 0.10+ script makes it: Newton
# with MUMPS. The line search matters here. Where a node turns from
# stick to slip the residual is only piecewise smooth, and a line search
# that asks the residual norm to fall (`bt`) takes steps of a tenth or
# less: 31 and 25 iterations on the first two slide increments below.
# The residual is the gradient of an energy (the bodies' and the
# penalty springs'), so PETSc's `bisection` line search, which looks for
# a zero of the slope $-\delta x \cdot F(x - \alpha \, \delta x)$ along
# the step, fits it: 10 and 8 iterations (it needs PETSc 3.23 or later;
# `bt` otherwise). An increment that needs more than 20 iterations is
# treated as failed (and cut back below).

line_search = "bisection" if hasattr(PETSc.SNESLineSearch.Type, "BISECTION") else "bt"
problem = NonlinearProblem(
    F, u, bcs=[held], petsc_options_prefix="demo_snes_",
    petsc_options={"snes_type": "newtonls", "snes_linesearch_type": line_search,
                   "snes_rtol": 1e-10, "snes_atol": 1e-9, "snes_max_it": 20,
                   "ksp_type": "preonly", "pc_type": "lu",
                   "pc_factor_mat_solver_type": "mumps"})

# The contact pair: the block's bottom edge (slave) on a rigid plane
# through the origin, its normal pointing into the block. Penalty
# $K = 100 E / h$ and stick slope $k_t = 10 E / h$ for the cell size $h$.

h = 1.0 / 20
pair = NodeToSurface(Surface(V, facet_tags, BOTTOM), rigid_plane([0.0, 0.0], [0.0, 1.0]),
                     E=E, K=100 * E / h, stick_slope=10 * E / h, mu=0.3)


# The script's own history: anything with `commit()` and `rollback()`.
# Here it logs each converged increment's contact force and counts the
# failed attempts; a plasticity model would copy its new quadrature-point
# state into the old one in `commit()` and back in `rollback()`.

class IncrementLog:
    """Converged contact forces (gdim,) per increment; failed attempts."""

    def __init__(self):
        self.forces: list[np.ndarray] = []
        self.failed = 0

    def commit(self):
        self.forces.append(pair.force())

    def rollback(self):
        self.failed += 1


log = IncrementLog()

# `add_contact` joins the pair to the problem. From now on the problem's
# SNES assembles the block as before and then adds the contact's forces
# and tangent; `contact.solve()` runs one increment: search, a matrix with
# the new couplings, `problem.solve()`, then `commit()` (the contact's
# and `log`'s) if SNES converged, else `rollback()` with the displacement
# restored to the increment's start.

contact = add_contact(problem, [pair], bcs=[held], history=[log])


# ## Load increments with cutbacks
#
# Pseudo-time $t \in [0, 1]$ presses, $t \in [1, 2]$ slides. A failed
# increment is halved and retried; the step grows back after a success.

# +
def plane_at(t: float) -> tuple[float, float]:
    """The plane's translation at pseudo-time t."""
    return (0.0, 0.05 * t) if t <= 1.0 else (0.3 * (t - 1.0), 0.05)


t = 0.0
for t_end, dt_max in ((1.0, 0.2), (2.0, 0.1)):
    dt = dt_max
    while t < t_end - 1e-12:
        step = min(dt, t_end - t)
        pair.obstacle_translation = plane_at(t + step)
        reason = contact.solve()
        if reason <= 0:
            if comm.rank == 0:
                print(f"t = {t + step:.4f}  SNES reason {reason}: cut back to dt = {step / 2:g}")
            dt = step / 2
            if dt < dt_max / 64:
                raise RuntimeError(f"no convergence at t = {t + step}")
            continue
        t, dt = t + step, min(2 * step, dt_max)
        fx, fy = log.forces[-1]
        closed, slipping = pair.counts()
        if comm.rank == 0:
            name = "press" if t <= 1.0 + 1e-12 else "slide"
            print(f"{name} t = {t:.4f}  SNES {contact.snes.getIterationNumber():2d}  "
                  f"F_n = {fy:.10g}  F_t = {fx:.10g}  F_t/F_n = {fx / fy:.10f}  "
                  f"contact {closed}, slip {slipping}")
if comm.rank == 0:
    print(f"{len(log.forces)} increments, {log.failed} cut back")
# -
