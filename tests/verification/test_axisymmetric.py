"""Axisymmetric bodies (``plane = "axisymmetric"``: meridian sections, r = x, z = y) against
closed forms, serially and under ``mpirun -n 2``.

* a homogeneous stretch ``F = diag(l_r, l_z, l_r)`` of a solid cylinder: exact with P1, so the
  reaction on its top is ``P_zz pi R^2`` (per full revolution) to round-off, for linear
  elasticity and both finite-strain models (their ``P`` written out here, independently of
  the package's UFL); a follower pressure on its top carries p times the deformed area;
* a shrink fit of two thick cylinders held axially: the contact pressure against Lamé
  (:func:`~dolfinx_friction.reference.analytic.shrink_fit_pressure`);
* a Hertz sphere on a rigid flat as a quarter disk: contact radius and peak pressure
  against Hertz, the contact forces against the reaction;
* the public UFL helpers (``revolution_weight``, ``axisymmetric_grad``) and
  ``NodeToSurface(axisymmetric=True)`` by hand reproduce the scene;
* the assembled Jacobian against finite differences (an O-ring section with friction);
* bad input: one line naming the key.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import ufl
from dolfinx import fem
from mpi4py import MPI

from dolfinx_friction import (BlockProblem, ContactSetupError, NodeToSurface, Surface,
                              axisymmetric_grad, revolution_weight, rigid_plane, solve_steps)
from dolfinx_friction import _compat as compat
from dolfinx_friction.fem.materials import bulk_modulus, lame
from dolfinx_friction.io import gmsh as gmsh_io
from dolfinx_friction.reference import meshes
from dolfinx_friction.reference.analytic import (
    effective_modulus, fit_elliptic, hertz_sphere, lame_cylinder_displacement,
    shrink_fit_pressure)
from dolfinx_friction.reference.compare import contact_state
from dolfinx_friction.rules import SceneError
from dolfinx_friction.scene.build import ContactProblem
from dolfinx_friction.scene.driver import Solver
from dolfinx_friction.scene.model import (BC, Body, ContactPair, Load, Rigid, RigidMotion,
                                          Scene, Step)
from dolfinx_friction.scene.runner import run
from dolfinx_friction.scene.validation import ModelError
from tests.finite_differences import scene_tangent_error

E, NU = 1000.0, 0.3


def _axisymmetric(name: str, model: str = "linear") -> Body:
    return Body(name, E, NU, plane="axisymmetric", model=model)


# ------------------------------------------------------------------ homogeneous stretch
def _first_piola(F: np.ndarray, model: str) -> np.ndarray:
    """``P`` of the package's models at a 3 x 3 ``F`` (closed forms)."""
    lam, mu = lame(E, NU)
    if model == "linear":
        eps = 0.5 * (F + F.T) - np.eye(3)
        return lam * np.trace(eps) * np.eye(3) + 2 * mu * eps
    if model == "saint-venant-kirchhoff":
        Eg = 0.5 * (F.T @ F - np.eye(3))
        return F @ (lam * np.trace(Eg) * np.eye(3) + 2 * mu * Eg)
    J, Finv_T = np.linalg.det(F), np.linalg.inv(F).T
    return (mu * J ** (-2 / 3) * (F - np.trace(F.T @ F) / 3 * Finv_T)
            + bulk_modulus(E, NU) * (J - 1) * J * Finv_T)


@pytest.mark.parametrize("model", ["linear", "saint-venant-kirchhoff", "neo-hookean"])
def test_homogeneous_stretch(shared_dir, model):
    """The cylinder [0, 1] x [0, 0.25] (r, z) stretched to F = diag(1.02, 0.97, 1.02): the
    hoop stretch 1 + u_r / r = 1.02 comes from u_r = 0.02 r alone.  Reactions on the top
    and the mantle are P_zz pi R^2 and P_rr 2 pi R H."""
    mesh = meshes.rectangle_2d(shared_dir / "cylinder.msh", n=(4, 2), quads=False)
    lr, lz, R, H = 1.02, 0.97, 1.0, 0.25
    scene = Scene(mesh=mesh, bodies=(_axisymmetric("block", model),),
                  steps=(Step("stretch", increments=2, bcs=(
                      BC("left", (0.0, None)), BC("bottom", (None, 0.0)),
                      BC("top", (None, (lz - 1) * H)), BC("right", ((lr - 1) * R, None)))),),)
    last = run(scene, write=False).increments[-1]
    P = _first_piola(np.diag([lr, lz, lr]), model)
    top, right = last.reactions["top"][1], last.reactions["right"][0]
    print(f"\n{model}: top {top:.10g} vs {P[1, 1] * math.pi * R ** 2:.10g}, mantle "
          f"{right:.10g} vs {P[0, 0] * 2 * math.pi * R * H:.10g}")
    assert top == pytest.approx(P[1, 1] * math.pi * R ** 2, rel=1e-9)
    assert right == pytest.approx(P[0, 0] * 2 * math.pi * R * H, rel=1e-9)


@pytest.mark.parametrize("model", ["saint-venant-kirchhoff", "neo-hookean"])
def test_follower_pressure_on_the_revolved_top(shared_dir, model):
    """A pressure p = 30 on the top of the finite-strain cylinder, free mantle: uniaxial
    Cauchy stress -p on the deformed top, whose radius is l_r R (l_r from P_rr = 0 and
    P_zz = -p l_r^2 for F = diag(l_r, l_z, l_r)), so the bottom carries p pi (l_r R)^2."""
    mesh = meshes.rectangle_2d(shared_dir / "cylinder.msh", n=(4, 2), quads=False)
    p, R = 30.0, 1.0
    scene = Scene(mesh=mesh, bodies=(_axisymmetric("block", model),),
                  steps=(Step("press", increments=3, bcs=(
                      BC("left", (0.0, None)), BC("bottom", (None, 0.0))),
                      loads=(Load("top", pressure=p),)),))
    bottom = run(scene, write=False).increments[-1].reactions["bottom"][1]

    def equations(stretches):
        lr, lz = stretches
        P = _first_piola(np.diag([lr, lz, lr]), model)
        return np.array([P[0, 0], P[1, 1] + p * lr ** 2])
    x = np.array([1.0, 1.0])
    for _ in range(30):  # Newton with a central-difference Jacobian
        J = np.column_stack([(equations(x + e) - equations(x - e)) / 2e-7
                             for e in 1e-7 * np.eye(2)])
        x = x - np.linalg.solve(J, equations(x))
    expected = p * math.pi * (x[0] * R) ** 2
    print(f"\n{model}: l_r = {x[0]:.6f}, l_z = {x[1]:.6f}, bottom {bottom:.10g} vs "
          f"{expected:.10g}")
    assert abs(equations(x)).max() < 1e-9 * p
    assert bottom == pytest.approx(expected, rel=1e-8)


# ------------------------------------------------------------------ shrink fit
R_I, R_C, R_O, DELTA = 1.0, 2.0, 3.0, 0.01


def _shrink_fit(mesh, **contact) -> Scene:
    held = tuple(BC(g, (None, 0.0)) for g in ("inner_bottom", "outer_bottom",
                                             "inner_top", "outer_top"))
    # by default a stiff penalty: the overclosure p / K is 1e-5 of the interference
    contact = contact or {"K": 1e7}
    return Scene(mesh=mesh, bodies=(_axisymmetric("inner"), _axisymmetric("outer")),
                 contacts=(ContactPair("inner_surface", "outer_surface", **contact),),
                 steps=(Step("fit", bcs=held),))


def _lame_model_pressure() -> float:
    """The pressure that closes the interference of the model's geometry: the slave face at
    b = r_c + delta, the master face at r_c carrying the same force (pressure p b / r_c)."""
    b = R_C + DELTA

    def closing(p):
        return (lame_cylinder_displacement(R_C, R_C, R_O, p * b / R_C, 0.0, E, NU, "held")
                - lame_cylinder_displacement(b, R_I, b, 0.0, p, E, NU, "held"))
    return DELTA / closing(1.0)


@pytest.mark.parametrize("order, n, tol, contact", [
    (1, 16, 3e-4, {}), (2, 8, 3e-5, {}), (1, 16, 3e-4, {"method": "augmented"})])
def test_shrink_fit_against_lame(shared_dir, order, n, tol, contact):
    """Two thick cylinders (r_i, r_c, r_o = 1, 2, 3, same E, nu) with the radial interference
    delta = 0.01, held axially (plane strain): every slave node carries Lamé's pressure;
    16 x 4 bilinear quadrilaterals per cylinder are 1.9e-4 off the Lamé value of the model's
    geometry (faces delta apart), 8 x 4 biquadratic ones 1.2e-5; that value is 0.29 % below
    the closed form of a small interference (faces at r_c).  A stiff penalty (K = 1e7), or
    the default K with the augmented Lagrangian (2.0e-4; the penalty alone: -1.4e-3)."""
    mesh = meshes.thick_cylinders(shared_dir / "fit.msh", R_I, R_C, R_O, DELTA, 0.5, (n, 4),
                                  order=order)
    state = contact_state(run(_shrink_fit(mesh, **contact), write=False))
    p = state["pressure"]
    closed_form = shrink_fit_pressure(DELTA, R_I, R_C, R_O, E, NU, "held")
    model = _lame_model_pressure()
    print(f"\nshrink fit: p = {p.mean():.6f} (spread {np.ptp(p):.1e}), Lamé {model:.6f} "
          f"({p.mean() / model - 1:+.2e}), closed form {closed_form:.6f} "
          f"({p.mean() / closed_form - 1:+.2e})")
    assert len(p) == 4 * order + 1 and np.ptp(p) < 1e-7 * p.mean()
    assert p.mean() == pytest.approx(model, rel=tol)
    assert p.mean() == pytest.approx(closed_form, rel=4e-3)
    # areas per full revolution: the slave face's revolved area 2 pi (r_c + delta) H
    assert state["area"].sum() == pytest.approx(2 * math.pi * (R_C + DELTA) * 0.5, rel=1e-12)


# ------------------------------------------------------------------ Hertz
R = 10.0


def _hertz(mesh, approach: float = 0.15) -> Scene:
    return Scene(mesh=mesh, bodies=(_axisymmetric("sphere"),),
                 rigids=(Rigid("floor", "plane", point=(0.0, 0.0), normal=(0.0, 1.0)),),
                 contacts=(ContactPair("sphere_surface", "floor"),),
                 steps=(Step("press", increments=4, bcs=(
                     BC("sphere_axis", (0.0, None)), BC("sphere_top", (None, -approach)))),))


def test_hertz_sphere_section(shared_dir):
    """The 3D demo's sphere (R = 10, E = 1000, nu = 0.3, approach 0.15, h = 0.12 at the pole)
    as a quarter disk of triangles: the elliptic fit of the nodal pressures is 0.1 % (a) and
    2.2 % (p0) off Hertz, the node on the axis 1.3 %.  (Refined, the fit converges to
    -0.8 % and +3.2 %: Hertz's half-space is 1.3 / 10 of a radius from exact at this load;
    the 3D demo's own fit: -0.3 % and +2.9 %.)  The contact forces (per full revolution) sum
    to the reaction."""
    mesh = meshes.sphere_section(shared_dir / "sphere.msh", R, h_contact=0.12)
    result = run(_hertz(mesh), write=False)
    state = contact_state(result)
    F = abs(result.increments[-1].reactions["sphere_top"][1])
    a, p0, _ = hertz_sphere(F, R, effective_modulus(E, NU))
    closed = state["status"] != 0
    r, p = state["X"][closed, 0], state["pressure"][closed]
    order = np.argsort(r)
    r, p = r[order], p[order]
    a_fit, p0_fit = fit_elliptic(r, p)
    print(f"\nHertz section: F = {F:.4f}, a {a_fit / a - 1:+.2%}, p0 {p0_fit / p0 - 1:+.2%}, "
          f"axis {p[0] / p0 - 1:+.2%}")
    assert abs(r[0]) < 1e-12 * R  # the node on the axis is a slave node with a (small) area
    assert state["normal_force"].sum() == pytest.approx(F, rel=1e-6)
    assert a_fit == pytest.approx(a, rel=0.005)
    assert p0_fit == pytest.approx(p0, rel=0.03)
    assert p[0] == pytest.approx(p0, rel=0.02)


def test_hertz_by_hand(shared_dir):
    """A FEniCSx script with the public helpers reproduces the scene's Hertz section: its
    own UFL residual weighted by ``revolution_weight`` with ``axisymmetric_grad``,
    ``NodeToSurface(axisymmetric=True)``; reactions of every increment to 1e-10."""
    path = meshes.sphere_section(shared_dir / "sphere.msh", R, h_contact=0.3)
    scene_run = run(_hertz(path), write=False)
    body = gmsh_io.load_mesh(path, ["sphere"]).bodies["sphere"]
    V = compat.vector_space(body.mesh, 1)
    u, v = fem.Function(V), ufl.TestFunction(V)
    lam, mu = lame(E, NU)

    def eps(w):
        return ufl.sym(axisymmetric_grad(w))
    sigma = lam * ufl.tr(eps(u)) * ufl.Identity(3) + 2 * mu * eps(u)
    dx = ufl.dx(metadata={"quadrature_degree": 2})  # the scene's rule (2k, interior points)
    residual = ufl.inner(sigma, eps(v)) * revolution_weight(body.mesh) * dx
    fdim = 1
    tags = {g: body.meshtags(fdim, [g])[0] for g in ("sphere_surface", "sphere_top",
                                                     "sphere_axis")}
    top = tags["sphere_top"].find(1)
    push = fem.Constant(body.mesh, 0.0)
    Vr, Vz = V.sub(0), V.sub(1)
    bcs = [fem.dirichletbc(0.0, fem.locate_dofs_topological(Vr, fdim, tags["sphere_axis"]
                                                            .find(1)), Vr),
           fem.dirichletbc(push, fem.locate_dofs_topological(Vz, fdim, top), Vz)]
    contact = NodeToSurface(Surface(V, tags["sphere_surface"], 1),
                            rigid_plane([0.0, 0.0], [0.0, 1.0]), E=E, axisymmetric=True)
    problem = BlockProblem([residual], [u], bcs, [contact])
    nodes = fem.locate_dofs_topological(V, fdim, top)
    nodes = nodes[nodes < V.dofmap.index_map.size_local]
    reactions = []

    def record(_):
        internal = problem.internal[problem.block_slice(0)].reshape(-1, 2)
        reactions.append(MPI.COMM_WORLD.allreduce(internal[nodes].sum(axis=0)))

    def press(t):
        push.value = -0.15 * t
    solve_steps(problem, press, 4, on_increment=record)
    assert len(reactions) == len(scene_run.increments) == 4
    for mine, inc in zip(reactions, scene_run.increments):
        ref = inc.reactions["sphere_top"]
        assert np.abs(mine - ref).max() <= 1e-10 * np.abs(ref).max()


# ------------------------------------------------------------------ tangent
@pytest.mark.parametrize("model", ["linear", "neo-hookean", "saint-venant-kirchhoff"])
def test_jacobian_matches_finite_differences(shared_dir, model):
    """An O-ring section squeezed by a rigid plane with friction (2 increments): the assembled
    Jacobian (bulk with the hoop term + contact on revolved areas, pairing frozen) is the
    derivative of the residual."""
    mesh = meshes.ring_section(shared_dir / "ring.msh", 5.0, 1.0, 0.25)
    scene = Scene(mesh=mesh, bodies=(_axisymmetric("ring", model),),
                  rigids=(Rigid("plane", "plane", point=(0.0, 1.0), normal=(0.0, -1.0)),),
                  contacts=(ContactPair("ring_surface", "plane", mu=0.3, K="calculix",
                                        stick_slope="calculix"),),
                  steps=(Step("squeeze", increments=2, bcs=(BC("ring_equator", (None, 0.0)),),
                              rigid=(RigidMotion("plane", displacement=(0.02, -0.1)),)),))
    problem = ContactProblem(scene)
    Solver(problem).run()
    error = scene_tangent_error(problem)
    print(f"\n{model}: FD rel error {error:.1e}")
    assert error < 1e-8, error


# ------------------------------------------------------------------ bad input
def test_axisymmetric_needs_a_2d_mesh(shared_dir):
    mesh = meshes.block_3d(shared_dir / "block.msh")
    scene = Scene(mesh=mesh, bodies=(_axisymmetric("block"),),
                  steps=(Step("s", bcs=(BC("bottom", (0.0, 0.0, 0.0)),)),))
    with pytest.raises(ModelError, match=r'^body\.0\.plane = "axisymmetric": .*3D'):
        run(scene, write=False)


def test_axisymmetric_nodes_left_of_the_axis(shared_dir):
    mesh = meshes.thick_cylinders(shared_dir / "fit.msh", -0.5, R_C, R_O, DELTA, 0.5, (4, 2))
    with pytest.raises(ModelError, match=r'^body\.0\.plane = "axisymmetric": .*r = x < 0'):
        run(_shrink_fit(mesh), write=False)


def test_axisymmetric_thickness_is_refused():
    with pytest.raises(SceneError, match=r"^body\.thickness = 2.*axisymmetric"):
        Body("b", E, NU, plane="axisymmetric", thickness=2.0)


def test_node_to_surface_axisymmetric_needs_2d(shared_dir):
    body = gmsh_io.load_mesh(meshes.block_3d(shared_dir / "block.msh"), ["block"]) \
        .bodies["block"]
    V = compat.vector_space(body.mesh, 1)
    tags, _ = body.meshtags(2, ["bottom"])
    with pytest.raises(ContactSetupError, match="axisymmetric.*2D"):
        NodeToSurface(Surface(V, tags, 1), rigid_plane([0, 0, 0], [0, 0, 1]), E=E,
                      axisymmetric=True)
