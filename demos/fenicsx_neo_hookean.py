"""A Neo-Hookean block pressed onto a rigid plane and dragged over it (mu = 0.3), with the
contact added to a plain FEniCSx problem: the script's own gmsh mesh, dolfinx space, UFL
residual and increment loop; dolfinx_friction only supplies the contact pair.

    python demos/fenicsx_neo_hookean.py [--cells N]       # serially
    mpirun -n 2 python demos/fenicsx_neo_hookean.py       # in parallel, the same numbers

The block (1 x 0.5, plane strain, E = 1000, nu = 0.3) is held at its top; the plane
rises by 10 % of the block's height (finite strain), then slides 0.3 to the right.  Once
every contact node slips, the drag over the press force is mu.  Writes
demos/fenicsx_neo_hookean_results/block.xdmf (displacement and contact fields per
increment, one time series) and, serially, a picture block.png.
"""
import argparse
import os
from pathlib import Path

if "DISPLAY" not in os.environ:  # off-screen pictures without an X server
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
try:  # VTK must be loaded before dolfinx
    import pyvista
except ImportError:
    pyvista = None
import gmsh
import numpy as np
import ufl
from dolfinx import fem
from dolfinx.io import XDMFFile
from mpi4py import MPI

from dolfinx_friction import BlockProblem, NodeToSurface, Surface, rigid_plane, solve_steps
from dolfinx_friction._compat import model_to_mesh, vector_space  # the same on dolfinx 0.5-0.11

parser = argparse.ArgumentParser()
parser.add_argument("--cells", type=int, default=20, help="cells along the block's width")
parser.add_argument("--no-picture", action="store_true", help="skip the picture")
parser.add_argument("--out", default=str(Path(__file__).with_name("fenicsx_neo_hookean_results")))
args = parser.parse_args()
comm = MPI.COMM_WORLD
BOTTOM, TOP = 1, 2

# -- the mesh: a quadrilateral block with tagged bottom and top edges (gmsh, rank 0)
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
if comm.rank == 0:
    gmsh.model.occ.addRectangle(0.0, 0.0, 0.0, 1.0, 0.5)
    gmsh.model.occ.synchronize()
    for curve in gmsh.model.getEntities(1):
        x, y, _ = gmsh.model.occ.getCenterOfMass(*curve)
        n = args.cells if abs(y - 0.25) > 0.2 else args.cells // 2
        gmsh.model.mesh.setTransfiniteCurve(curve[1], n + 1)
        if abs(y) < 1e-9 or abs(y - 0.5) < 1e-9:
            gmsh.model.addPhysicalGroup(1, [curve[1]], BOTTOM if y < 0.25 else TOP)
    gmsh.model.mesh.setTransfiniteSurface(1)
    gmsh.model.mesh.setRecombine(2, 1)
    gmsh.model.addPhysicalGroup(2, [1], 1)
    gmsh.model.mesh.generate(2)
mesh, _, facets = model_to_mesh(gmsh.model, comm, 0, gdim=2)
gmsh.finalize()

# -- the user's own physics: compressible Neo-Hookean (CalculiX's NEO HOOKE), plane strain
E, nu = 1000.0, 0.3
mu, kappa = E / (2 * (1 + nu)), E / (3 * (1 - 2 * nu))
V = vector_space(mesh, 1)
u, v = fem.Function(V, name="displacement"), ufl.TestFunction(V)
F2 = ufl.variable(ufl.Identity(2) + ufl.grad(u))
F = ufl.as_matrix([[F2[0, 0], F2[0, 1], 0], [F2[1, 0], F2[1, 1], 0], [0, 0, 1]])
J = ufl.det(F)
W = mu / 2 * (J ** (-2 / 3) * ufl.tr(F.T * F) - 3) + kappa / 2 * (J - 1) ** 2
residual = ufl.inner(ufl.diff(W, F2), ufl.grad(v)) * ufl.dx
held = fem.dirichletbc(np.zeros(2), fem.locate_dofs_topological(V, 1, facets.find(TOP)), V)

# -- the contact: the block's bottom on a rigid plane that rises, then slides
h = 1.0 / args.cells  # the cell size: penalties in units of E / h
contact = NodeToSurface(Surface(V, facets, BOTTOM), rigid_plane([0.0, 0.0], [0.0, 1.0]),
                        E=E, K=100 * E / h, stick_slope=10 * E / h, mu=0.3)
problem = BlockProblem([residual], [u], [held], [contact])
out = Path(args.out)
xdmf = XDMFFile(comm, str(out / "block.xdmf"), "w")
xdmf.write_mesh(mesh)


def rise(t):
    contact.obstacle_translation = (0.0, 0.05 * t)


def slide(t):
    contact.obstacle_translation = (0.3 * t, 0.05)


def reporter(step, name):
    def report(increment):
        force = contact.force()  # of the plane on the block
        closed, slipping = contact.counts()
        if comm.rank == 0:
            print(f"{name} t = {increment.t:5.3f}  Newton {increment.iterations}  "
                  f"F_n = {force[1]:.10g}  F_t = {force[0]:.10g}  "
                  f"F_t/F_n = {force[0] / force[1]:.10f}  contact {closed}, slip {slipping}")
        for f in [u, *contact.fields().values()]:
            xdmf.write_function(f, step + increment.t)
    return report


solve_steps(problem, rise, 5, on_increment=reporter(0, "press"))
solve_steps(problem, slide, 10, on_increment=reporter(1, "slide"))
xdmf.close()

if comm.size == 1 and pyvista is not None and not args.no_picture:
    from dolfinx_friction._compat import vtk_mesh  # the deformed block, by contact status
    grid = pyvista.UnstructuredGrid(*vtk_mesh(V))
    grid.points[:, :2] += u.x.array.reshape(-1, 2)
    grid.point_data["status"] = contact.fields()["status"].x.array
    plotter = pyvista.Plotter(off_screen=True, window_size=(900, 450))
    plotter.add_mesh(grid, scalars="status", show_edges=True, clim=[-1, 2], cmap="coolwarm",
                     show_scalar_bar=False)
    plotter.add_text("contact status: blue none/open ... red slip", font_size=10)
    plotter.view_xy()
    plotter.screenshot(str(out / "block.png"))
    print(f"picture: {out / 'block.png'}")
