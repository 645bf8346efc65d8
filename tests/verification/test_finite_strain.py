"""Finite-strain bodies (scene key ``model``) against closed forms and identities.

* Homogeneous compression of a block on a frictionless rigid plane, to 40 % of its height,
  rollers on the symmetry faces: the deformation is homogeneous, so P1 and P2 represent it
  exactly and the top force must equal the nominal stress of the model at the measured
  stretch (the lateral stretch solved from zero lateral stress) times the reference area.
  Neo-Hooke (CalculiX's NEO HOOKE) and Saint Venant-Kirchhoff, plane strain and 3D, P1 and
  P2.  Measured: 4e-16 .. 5e-12 relative (the Newton tolerance is 1e-9).
* A rigid rotation of a prestressed Neo-Hookean body changes no stress invariant.
* An element that inverts is cut back, then stops the run with one line naming the body.
Serial and under ``mpirun -n 2``.
"""
from __future__ import annotations

import numpy as np
import pytest
import ufl
from scipy.optimize import brentq

from dolfinx_friction.scene.runner import run
from dolfinx_friction.scene.driver import ConvergenceError
from dolfinx_friction.scene.model import BC, Body, ContactPair, Output, Rigid, Scene, Step
from dolfinx_friction.reference.compare import contact_state
from dolfinx_friction.reference import meshes

E, NU = 1000.0, 0.3
MU, LAM = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
KAPPA = E / (3 * (1 - 2 * NU))


def nominal_stress(model: str, stretches: np.ndarray, i: int) -> float:
    """``dW/dlambda_i``: the nominal (first Piola-Kirchhoff) principal stress."""
    s = np.asarray(stretches, dtype=float)
    if model == "neo-hookean":
        J, I1 = s.prod(), (s ** 2).sum()
        return (MU / 2 * J ** (-2 / 3) * (2 * s[i] - 2 / 3 * I1 / s[i])
                + KAPPA * (J - 1) * J / s[i])
    green = (s ** 2 - 1) / 2
    return (LAM * green.sum() + 2 * MU * green[i]) * s[i]


def uniaxial_force(model: str, axial: float, dim: int) -> float:
    """Compressive force per unit reference area at the axial stretch, laterally free
    (plane strain: the out-of-plane stretch is 1)."""
    def stretches(lateral):
        return [lateral, axial, 1.0] if dim == 2 else [lateral, lateral, axial]
    lateral = brentq(lambda a: nominal_stress(model, stretches(a), 0), 0.5, 3.0)
    return -nominal_stress(model, stretches(lateral), 1 if dim == 2 else 2)


def compression_scene(path, model: str, dim: int, degree: int):
    if dim == 2:
        mesh, H = meshes.rectangle_2d(path / "rect.msh", n=(4, 2)), 0.25
        bcs = (BC("left", (0.0, None)), BC("top", (None, -0.4 * H)))
        floor = Rigid("floor", "plane", point=(0.0, 0.0), normal=(0.0, 1.0))
    else:
        mesh, H = meshes.block_3d(path / "block.msh", n=(2, 2, 2)), 0.5
        bcs = (BC("side_x0", (0.0, None, None)), BC("side_y0", (None, 0.0, None)),
               BC("top", (None, None, -0.4 * H)))
        floor = Rigid("floor", "plane", point=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0))
    scene = Scene(mesh=mesh, bodies=(Body("block", E, NU, degree=degree, model=model),),
                  rigids=(floor,), contacts=(ContactPair("bottom", "floor", K=2000 * E),),
                  steps=(Step("press", increments=8, bcs=bcs),),
                  output=Output(reactions=("top",)))
    return scene, H


@pytest.mark.parametrize("model", ["neo-hookean", "saint-venant-kirchhoff"])
@pytest.mark.parametrize("dim, degree", [(2, 1), (2, 2), (3, 1), (3, 2)])
def test_homogeneous_compression_matches_the_closed_form(shared_dir, model, dim, degree):
    scene, H = compression_scene(shared_dir, model, dim, degree)
    result = run(scene, write=False)
    gaps = contact_state(result)["gap"]
    assert np.ptp(gaps) < 1e-12 * H  # homogeneous: one overclosure everywhere
    axial = (H - 0.4 * H - gaps.mean()) / H  # the plane is at 0: the gap is the bottom's height
    force = -result.increments[-1].reactions["top"][dim - 1]
    expected = uniaxial_force(model, axial, dim)  # reference area 1
    print(f"\n{model} {dim}D P{degree}: stretch {axial:.4f}, force {force:.12g}, closed form "
          f"{expected:.12g}, rel. difference {abs(force / expected - 1):.1e}")
    assert axial < 0.61
    assert force == pytest.approx(expected, rel=1e-9)


def test_rigid_rotation_changes_no_stress_invariant(comm):
    """Frame indifference of the Neo-Hookean body: a deformed (prestressed) block, then the
    same configuration rotated rigidly by 50 degrees.  The nodal internal forces rotate with
    it and the Cauchy stress invariants (trace, von Mises) at every quadrature point are
    unchanged, to 1e-10 of their size."""
    from dolfinx import fem, mesh

    from dolfinx_friction import _compat as compat
    from dolfinx_friction.scene.build import deformation_gradient, strain_energy
    domain = mesh.create_rectangle(comm, [[0.0, 0.0], [1.0, 0.5]], [4, 2],
                                   mesh.CellType.quadrilateral)
    V = compat.vector_space(domain, 1)
    u, v = fem.Function(V), ufl.TestFunction(V)
    F, F3 = deformation_gradient(u, 2)
    P = ufl.diff(strain_energy(Body("block", E, NU, model="neo-hookean"), F3), F)
    internal = compat.form(ufl.inner(P, ufl.grad(v)) * ufl.dx)
    sigma = P * F.T / ufl.det(F)
    dev = sigma - ufl.tr(sigma) / 3 * ufl.Identity(2)  # plane strain: sigma_33 enters too
    invariants = compat.quadrature_expression(ufl.as_vector([ufl.tr(sigma), ufl.inner(dev, dev)]),
                                              domain, 2)
    X = V.tabulate_dof_coordinates()[:, :2]
    u.x.array[:] = np.column_stack([0.1 * X[:, 0] * X[:, 1] - 0.05 * X[:, 1],
                                    -0.2 * X[:, 1] ** 2 + 0.03 * X[:, 0]]).ravel()
    before = (compat.assemble_vector(internal).reshape(-1, 2),
              compat.evaluate_on_owned_cells(invariants, domain))
    a = np.deg2rad(50.0)
    R = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    x = X + u.x.array.reshape(-1, 2)
    u.x.array[:] = (x @ R.T - X).ravel()
    after = (compat.assemble_vector(internal).reshape(-1, 2),
             compat.evaluate_on_owned_cells(invariants, domain))
    scale = np.abs(before[0]).max()
    assert scale > 1.0  # prestressed
    np.testing.assert_allclose(after[0], before[0] @ R.T, rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(after[1], before[1], rtol=0,
                               atol=1e-10 * np.abs(before[1]).max())


@pytest.mark.parametrize("model", ["saint-venant-kirchhoff", "neo-hookean"])
def test_an_inverted_element_stops_the_run_naming_the_body(shared_dir, model):
    """Pressing a 0.25-high block by 0.3 onto a floor inverts its elements before the end
    (Neo-Hooke's energy barrier keeps ``det F > 0`` while the block can spread: its bottom
    is held): the last increment fails after all cutbacks, and the error names the body,
    step and increment.  Saint Venant-Kirchhoff's guard checks every iterate; Neo-Hooke's
    residual is not finite there, and its guard names why."""
    mesh = meshes.rectangle_2d(shared_dir / "rect.msh", n=(4, 2))
    scene = Scene(
        mesh=mesh, bodies=(Body("block", E, NU, model=model),),
        rigids=(Rigid("floor", "plane", point=(0.0, 0.0), normal=(0.0, 1.0)),),
        contacts=(ContactPair("bottom", "floor"),),
        steps=(Step("crush", max_cutbacks=2, bcs=(BC("left", (0.0, None)),
                                                  BC("top", (None, -0.3))) + (
            (BC("bottom", (0.0, 0.0)),) if model == "neo-hookean" else ())),))
    with pytest.raises(ConvergenceError) as info:
        run(scene, write=False)
    message = str(info.value)
    assert "step 0 ('crush'), increment " in message and "at t = " in message
    assert "body 'block' inverts (det F <= 0)" in message
