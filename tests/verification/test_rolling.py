"""A rigid wheel (a circle, radius R) pressed into a thick, nearly incompressible elastic layer
(plane strain, nu = 0.49, P2) and moved along it by d: rolling freely (rotation theta = -d/R,
clockwise while it moves towards +x, so the material point of the wheel at the contact stands
still) it carries almost no tangential force; with its rotation locked (theta = 0) it slides,
every contact node slips, and it carries mu times the normal force.  Its moment about its
centre is the friction force times R.

The layer is the uncoupled configuration of rolling contact: a half-space (thickness 1 against
a contact half-width of about 0.04) of a nearly incompressible material, whose Dundurs
constant against a rigid body, beta = (1 - 2 nu) / (2 (1 - nu)) = 0.02, nearly vanishes, so
normal pressure moves no surface point tangentially.  (With nu = 0.3, beta = 0.29, the same
free rolling carries F_t / F_n = 0.15: the compressed surface under the wheel creeps.)
Driven with creep (turning faster than it rolls), the wheel carries Carter's creep force.
Serial and under ``mpirun -n 2``.
"""
from __future__ import annotations

import csv

import numpy as np
import pytest

from dolfinx_friction.reference import meshes
from dolfinx_friction.reference.analytic import (carter_creep_force, carter_saturation_creep,
                                                 effective_modulus, hertz_line)
from dolfinx_friction.reference.compare import contact_state
from dolfinx_friction.scene.model import (BC, Body, ContactPair, Output, Rigid, RigidMotion,
                                          Scene, Step)
from dolfinx_friction.scene.runner import run

E, NU, MU, R = 1000.0, 0.49, 0.3, 1.0
X0, DEPTH = 1.0, 0.003  # the wheel's first centre (x: the layer's middle), how far it is pressed


def wheel_scene(mesh, d: float, theta: float, increments: int, out=None) -> Scene:
    """The wheel pressed in (2 increments), then moved by ``d`` along x while it turns by
    ``theta`` (radians, counter-clockwise)."""
    return Scene(
        mesh=mesh, bodies=(Body("block", E, NU, degree=2),),
        rigids=(Rigid("wheel", "sphere", center=(X0, R), radius=R),),
        contacts=(ContactPair("top", "wheel", mu=MU),),
        steps=(Step("press", increments=2, bcs=(BC("bottom", (0.0, 0.0)),),
                    rigid=(RigidMotion("wheel", displacement=(0.0, -DEPTH)),)),
               Step("roll", increments=increments,
                    rigid=(RigidMotion("wheel", displacement=(d, -DEPTH), rotation=theta),))),
        **({} if out is None else {"output": Output(dir=str(out), fields=False)}))


def layer(directory, d: float):
    return meshes.rolling_layer(directory / "layer.msh", track=(X0 - 0.25, X0 + d + 0.25),
                                h_track=0.01)


def test_free_rolling_carries_almost_no_tangential_force(shared_dir):
    """Rolling freely over 0.3 (8 contact half-widths), F_t / F_n stays below 0.012 (3.8 %
    of mu; it drifts as the layer, 2 wide, is sheared between the wheel and its bottom).  A
    wheel turning 0.1 % faster (creep 1e-3) carries 5 times more: the slip follows the
    wheel's rotation to much better than that."""
    d, n = 0.3, 24
    mesh = layer(shared_dir, d)
    ratios = {}
    for creep in (0.0, 1e-3):
        result = run(wheel_scene(mesh, d, -(1 + creep) * d / R, n), write=False)
        ratios[creep] = np.array([inc.rigid_f["wheel"][0] / -inc.rigid_f["wheel"][1]
                                  for inc in result.increments])
    free, faster = (np.abs(ratios[c]).max() for c in (0.0, 1e-3))
    print(f"\nfree rolling: F_t/F_n after the press {ratios[0.0][1]:+.1e}, largest while "
          f"rolling {free:.2e}, at the end {ratios[0.0][-1]:+.2e} (mu = {MU}); turning 0.1 % "
          f"faster: largest {faster:.2e}")
    assert free < 0.012  # measured 8.3e-3
    assert faster > 4 * free


def test_locked_wheel_slides_at_mu_with_moment_friction_times_radius(shared_dir):
    d = 0.1
    result = run(wheel_scene(layer(shared_dir, d), d, 0.0, 4, out=shared_dir / "out"))
    last = result.increments[-1]
    st = contact_state(result)
    closed = st["status"] > 0
    F_T, F_N = st["tangential_force"][closed], st["normal_force"][closed]
    assert closed.sum() > 10 and (st["status"][closed] == 2).all()  # full slip
    friction = np.linalg.norm(F_T, axis=1).sum()
    assert friction == pytest.approx(MU * F_N.sum(), rel=1e-12)
    F, M = last.rigid_f["wheel"], last.rigid_m["wheel"]
    # exactly (round-off): each node's contact force acts at R n from the centre c, n the
    # direction from c to the node; ContactState.force is the force that holds the wheel there
    own = result.problem.pair_of(result.problem.scene.contacts[0]).state()
    v = own.x[own.has_element] - (np.array([X0, R]) + last.rigid_u["wheel"])
    n, f = v / np.linalg.norm(v, axis=1)[:, None], own.force[own.has_element]
    arms = result.problem.comm.allreduce(float(np.sum(n[:, 0] * f[:, 1] - n[:, 1] * f[:, 0])))
    assert M[0] == pytest.approx(R * arms, rel=1e-12)
    # the drive holds the wheel against the layer's friction (towards -x at its bottom): it
    # pulls it forward (F_x > 0) and its moment about the centre is counter-clockwise,
    # M_z = +R * friction (each contact force acts at R from the centre, its normal part
    # through it)
    print(f"\nlocked: sum|F_T| / (mu sum F_N) - 1 = {friction / (MU * F_N.sum()) - 1:.1e}; "
          f"M_z / (R sum|F_T|) - 1 = {M[0] / (R * friction) - 1:.2e}; resultant F_x / -F_y "
          f"= {F[0] / -F[1]:.6f}, M_z / (R F_x) - 1 = {M[0] / (R * F[0]) - 1:.2e}")
    # to 1e-3 (measured 1.9e-4): a node's friction force keeps a small normal component, as
    # its elastic tangential gap is not turned with its normal (docs/theory.md §10.12), which
    # turns by d / (4 R) per increment under the sliding wheel
    assert M[0] == pytest.approx(R * friction, rel=1e-3)
    # the resultant: the normals tilt over the contact (measured +1.4e-3 and -5.7e-4)
    assert F[0] / -F[1] == pytest.approx(MU, rel=5e-3)
    assert M[0] == pytest.approx(R * F[0], rel=5e-3)
    if result.problem.comm.rank == 0:
        with open(shared_dir / "out" / "history.csv") as f:
            row = list(csv.DictReader(f))[-1]
        assert float(row["M_wheel_z"]) == pytest.approx(M[0], rel=1e-12)


def test_driven_wheel_carries_carters_creep_force(shared_dir):
    """Turning 0.6 % faster than it rolls (creep xi = xi_sat / 2, xi_sat = mu a / R with the
    Hertz half-width a of the normal force), over 0.6 (15 half-widths) on a layer 3 wide, the
    wheel carries F_t / (mu F_n) = 0.731 against Carter's 1 - (1 - xi/xi_sat)^2 = 0.749
    (steady within 0.3 %; rolled over 1.5 on a layer 3.5 wide, 0.726 against 0.741, and
    0.399 against 0.432 at xi_sat / 4, 0.927 against 0.930 at 3 xi_sat / 4: the layer keeps
    a few hundredths of mu F_n of what the press left, as free rolling shows)."""
    d, n = 0.6, 24
    mesh = meshes.rolling_layer(shared_dir / "wide.msh", width=3.0,
                                track=(X0 - 0.25, X0 + d + 0.25), h_track=0.01)
    E_star = effective_modulus(E, NU)  # a rigid wheel: 1/E* = (1 - nu^2)/E
    creep = 0.5 * carter_saturation_creep(MU, hertz_line(1.75, R, E_star).a, R)
    result = run(wheel_scene(mesh, d, -(1 + creep) * d / R, n), write=False)
    ratios = [-inc.rigid_f["wheel"][0] / (MU * -inc.rigid_f["wheel"][1])
              for inc in result.increments]
    a = hertz_line(-result.increments[-1].rigid_f["wheel"][1], R, E_star).a
    carter = carter_creep_force(creep, MU, a, R)
    print(f"\ndriven at xi/xi_sat = {creep / carter_saturation_creep(MU, a, R):.3f}: "
          f"F_t/(mu F_n) = {ratios[-1]:.4f}, Carter {carter:.4f}, last increments "
          f"{' '.join(f'{r:.4f}' for r in ratios[-4:])}")
    assert abs(ratios[-1] - carter) < 0.03  # measured 0.018
    assert abs(ratios[-1] - ratios[-2]) < 0.005  # steady


def test_3d_cylinder_turned_by_a_rotation_vector(shared_dir):
    """3D: a rigid cylinder along y (R = 1) pressed into a block [0, 1] x [0, 1] x [0, 0.5]
    (20 x 4 x 4 hexahedra, nu = 0.3) and moved by 0.2 along x, with its rotation locked: it
    slides at F_x / -F_z = mu (0.298, the normals tilting) with the moment M_y = -R F_x about
    its axis (contact below it); turned by the rotation vector [0, d/R, 0] it rolls: F_x /
    -F_z = -0.061 (a coarse mesh, and nu = 0.3 couples normal pressure and tangential
    surface strain: the 2D layer's fine mesh gives 0.15)."""
    mesh = meshes.block_3d(shared_dir / "block.msh", n=(20, 4, 4))
    d, ratios = 0.2, {}
    for mode, theta in (("rolling", d / R), ("locked", 0.0)):
        scene = Scene(
            mesh=mesh, bodies=(Body("block", E, 0.3),),
            rigids=(Rigid("wheel", "cylinder", point=(0.4, 0.5, 0.5 + R), axis=(0.0, 1.0, 0.0),
                          radius=R),),
            contacts=(ContactPair("top", "wheel", mu=MU),),
            steps=(Step("press", increments=2, bcs=(BC("bottom", (0.0, 0.0, 0.0)),),
                        rigid=(RigidMotion("wheel", displacement=(0.0, 0.0, -0.005)),)),
                   Step("roll", increments=8,
                        rigid=(RigidMotion("wheel", displacement=(d, 0.0, -0.005),
                                           rotation=(0.0, theta, 0.0)),))))
        last = run(scene, write=False).increments[-1]
        F, M = last.rigid_f["wheel"], last.rigid_m["wheel"]
        ratios[mode] = F[0] / -F[2]
        if mode == "locked":
            assert M[1] == pytest.approx(-R * F[0], rel=0.02)  # measured 0.8 %
            assert abs(M[0]) < 1e-9 * abs(M[1]) and abs(M[2]) < 1e-9 * abs(M[1])
    print(f"\n3D cylinder: F_x/-F_z locked {ratios['locked']:.4f}, rolling "
          f"{ratios['rolling']:+.4f}")
    assert ratios["locked"] == pytest.approx(MU, rel=0.02)  # measured 0.8 % below
    assert abs(ratios["rolling"]) < 0.25 * ratios["locked"]  # measured 0.20
