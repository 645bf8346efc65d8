"""The public API, used as a FEniCSx script would use it, reproduces the scene path.

``demos/incline.toml`` (a plane-strain block on a rigid slope: traction load, a bc on one
component, friction) and ``demos/sliding_block.toml`` (two 3D bodies, friction) are solved
twice: by the command line's scene path, and by hand from the same mesh with the user's own
UFL residuals (the load as a UFL traction), dolfinx DirichletBCs on (sub)spaces, one
``NodeToSurface`` and ``solve_steps`` per step.  The reactions of every increment agree to
1e-10 relative to their largest component.  Serial and under ``mpirun -n 2``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import ufl
from dolfinx import fem
from mpi4py import MPI

from dolfinx_friction import BlockProblem, NodeToSurface, Surface, rigid_plane, solve_steps
from dolfinx_friction import _compat as compat
from dolfinx_friction.io import gmsh as gmsh_io
from dolfinx_friction.scene.runner import run

DEMOS = Path(__file__).resolve().parents[2] / "demos"


def elastic(u, E, nu):
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    eps = ufl.sym(ufl.grad(u))
    return lam * ufl.tr(eps) * ufl.Identity(len(u)) + 2 * mu * eps


def group(body: gmsh_io.BodyMesh, name: str):
    """(facet tags with value 1 on the group, its facets)."""
    tags, _ = body.meshtags(body.mesh.topology.dim - 1, [name])
    return tags, tags.find(1)


def reaction(problem: BlockProblem, k: int, V, facets) -> np.ndarray:
    """Sum of the internal forces at the owned nodes of some facets of body ``k``."""
    fdim = V.mesh.topology.dim - 1
    nodes = fem.locate_dofs_topological(V, fdim, facets)
    nodes = nodes[nodes < V.dofmap.index_map.size_local]
    d = V.mesh.geometry.dim
    internal = problem.internal[problem.block_slice(k)].reshape(-1, d)
    return MPI.COMM_WORLD.allreduce(internal[nodes].sum(axis=0))


def compare(by_hand: list, scene_run, groups: list[str]) -> float:
    worst = 0.0
    assert len(by_hand) == len(scene_run.increments)
    for mine, inc in zip(by_hand, scene_run.increments):
        for g, r in zip(groups, mine):
            ref = inc.reactions[g]
            worst = max(worst, np.abs(r - ref).max() / np.abs(ref).max())
    return worst


def test_incline_by_hand():
    scene_run = run(DEMOS / "incline.toml", write=False)
    body = gmsh_io.load_mesh(DEMOS / "incline.msh", ["block"]).bodies["block"]
    V = compat.vector_space(body.mesh, 1)
    u, v = fem.Function(V), ufl.TestFunction(V)
    bottom_tags, _ = group(body, "block_bottom")
    top_tags, top = group(body, "block_top")
    traction = fem.Constant(body.mesh, np.zeros(2))
    ds = ufl.Measure("ds", domain=body.mesh, subdomain_data=top_tags)(1)
    residual = ufl.inner(elastic(u, 1e4, 0.3), ufl.sym(ufl.grad(v))) * ufl.dx \
        - ufl.inner(traction, v) * ds
    push = fem.Constant(body.mesh, 0.0)
    Vx = V.sub(0)
    bc = fem.dirichletbc(push, fem.locate_dofs_topological(Vx, 1, top), Vx)
    slope = rigid_plane([0.0, 0.0], [-0.09950371902099892, 0.9950371902099892])
    contact = NodeToSurface(Surface(V, bottom_tags, 1), slope, E=1e4, mu=0.3, sigma_inf=0.025)
    problem = BlockProblem([residual], [u], [bc], [contact])
    reactions = []

    def record(_):
        reactions.append([reaction(problem, 0, V, top)])

    def load(t):
        traction.value[:] = (0.0, -10.0 * t)

    def push_up(t):
        push.value = 0.5 * t
    solve_steps(problem, load, 1, on_increment=record)
    solve_steps(problem, push_up, 10, on_increment=record)
    worst = compare(reactions, scene_run, ["block_top"])
    print(f"\nincline: worst reaction difference {worst:.1e}")
    assert worst < 1e-10


@pytest.mark.slow
def test_sliding_block_by_hand():
    scene_run = run(DEMOS / "sliding_block.toml", write=False)
    bodies = gmsh_io.load_mesh(DEMOS / "sliding_block.msh", ["block", "foundation"]).bodies
    spaces = [compat.vector_space(bodies[b].mesh, 1) for b in ("block", "foundation")]
    us = [fem.Function(V) for V in spaces]
    residuals = [ufl.inner(elastic(w, 210000.0, 0.3), ufl.sym(ufl.grad(ufl.TestFunction(V))))
                 * ufl.dx for w, V in zip(us, spaces)]
    slave_tags, _ = group(bodies["block"], "block_bottom")
    master_tags, _ = group(bodies["foundation"], "foundation_top")
    _, top = group(bodies["block"], "block_top")
    _, base = group(bodies["foundation"], "foundation_bottom")
    motion = fem.Constant(bodies["block"].mesh, np.zeros(3))
    bcs = [fem.dirichletbc(motion, fem.locate_dofs_topological(spaces[0], 2, top), spaces[0]),
           fem.dirichletbc(np.zeros(3), fem.locate_dofs_topological(spaces[1], 2, base),
                           spaces[1])]
    contact = NodeToSurface(Surface(spaces[0], slave_tags, 1), Surface(spaces[1], master_tags, 1),
                            E=210000.0, mu=0.3)  # the default K and lambda, as the scene
    problem = BlockProblem(residuals, us, bcs, [contact])
    reactions = []

    def record(_):
        reactions.append([reaction(problem, 0, spaces[0], top),
                          reaction(problem, 1, spaces[1], base)])

    def press(t):
        motion.value[:] = (0.0, 0.0, -0.02 * t)

    def slide(t):
        motion.value[:] = (10.0 * t, 0.0, -0.02)
    solve_steps(problem, press, 1, on_increment=record)
    solve_steps(problem, slide, 10, on_increment=record)
    worst = compare(reactions, scene_run, ["block_top", "foundation_bottom"])
    print(f"\nsliding block: worst reaction difference {worst:.1e}")
    assert worst < 1e-10
