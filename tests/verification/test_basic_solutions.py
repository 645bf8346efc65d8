"""Exact solutions of small scenes: full slip, uniform penetration, Newton's convergence order."""
from __future__ import annotations

import numpy as np
import pytest

from dolfinx_friction.scene.runner import run
from dolfinx_friction.contact.laws import Linear
from dolfinx_friction.scene.model import BC, Body, ContactPair, Load, Rigid, Scene, Step
from dolfinx_friction.reference.compare import contact_state
from dolfinx_friction.reference import meshes

E, NU = 1000.0, 0.3


def _floor_2d() -> Rigid:
    return Rigid("floor", "plane", point=(0.0, 0.0), normal=(0.0, 1.0))


def test_full_slip_force_ratio_is_mu(shared_dir):
    """A 2D block dragged over a rigid floor: tangential/normal reaction = mu (all nodes slip)."""
    mesh = meshes.rectangle_2d(shared_dir / "rect.msh", n=(8, 2))
    mu = 0.3
    scene = Scene(
        mesh=mesh, bodies=(Body("block", E, NU),), rigids=(_floor_2d(),),
        contacts=(ContactPair("bottom", "floor", mu=mu),),
        steps=(Step("press", bcs=(BC("top", (0.0, -0.005)),)),
               Step("slide", increments=3, bcs=(BC("top", (0.05, -0.005)),))))
    result = run(scene, write=False)
    last = result.increments[-1]
    assert last.slipping == last.active == 9
    R = last.reactions["top"]
    assert abs(abs(R[0] / R[1]) - mu) <= 1e-8 * mu
    F = last.rigid_f["floor"]  # the force of the floor's constraint on the floor
    np.testing.assert_allclose(F, -R, rtol=1e-9)


def test_uniform_pressure_penetration(shared_dir):
    """Uniform pressure p on a block on a frictionless rigid floor: the floor carries p L, every
    slave node the same pressure, and the nodes penetrate by the inverse of the linear law,
    d = (p + sigma_inf)/K for d >> eps.  (A_p is measured on the faces as deformed at the
    start of the last of the 2 increments, under p / 2, which the Poisson effect widens by
    nu (1 + nu) p / (2 E) in plane strain: the contact pressure is
    p / (1 + nu (1 + nu) p / (2 E)).)"""
    mesh = meshes.rectangle_2d(shared_dir / "rect.msh", n=(8, 2))
    p, K, sigma_inf = 2.0, 5.0e4, E / 70000.0
    scene = Scene(
        mesh=mesh, bodies=(Body("block", E, NU),), rigids=(_floor_2d(),),
        contacts=(ContactPair("bottom", "floor", K=K),),
        steps=(Step("load", increments=2, bcs=(BC("left", (0.0, None)),),
                    loads=(Load("top", pressure=p),)),))
    result = run(scene, write=False)
    state = contact_state(result)
    pressure, gaps = state["pressure"], state["gap"]
    assert len(pressure) == 9
    assert state["normal_force"].sum() == pytest.approx(p * 1.0, rel=1e-9)
    np.testing.assert_allclose(pressure, pressure.mean(), rtol=1e-9)
    assert pressure.mean() == pytest.approx(p / (1 + NU * (1 + NU) * p / (2 * E)), rel=1e-6)
    law_p, _ = Linear(K, sigma_inf).pressure(-gaps)
    np.testing.assert_allclose(law_p, pressure, rtol=1e-9)
    d = (pressure.mean() + sigma_inf) / K
    np.testing.assert_allclose(-gaps, d, rtol=1e-5)
    np.testing.assert_allclose(-gaps, p / K, rtol=1.1 * sigma_inf / p + 1e-3)


def observed_order(residuals: list[float]) -> float:
    """Order q of e_(k+1) = e_k^q, e = r/r_0, over the last two iterates above round-off."""
    r0 = residuals[0]
    e = [r / r0 for r in residuals[1:] if r > 1e-10 * r0]
    return np.log(e[-1]) / np.log(e[-2])


def _sliding_boxes(mesh, tangent: str) -> Scene:
    tol = dict(newton_rtol=1e-11, newton_atol=1e-14)  # round-off floor: 1e-13 relative
    return Scene(
        mesh=mesh, bodies=(Body("block", E, NU), Body("foundation", E, NU)),
        # CalculiX's K and lambda (50 E, E/2): the slide's first increment sticks (with the
        # default lambda = E/h, 8 times stiffer here, it slips)
        contacts=(ContactPair("block_bottom", "foundation_top", mu=0.3, tangent=tangent,
                              K="calculix", stick_slope="calculix"),),
        steps=(Step("press", bcs=(BC("foundation_bottom", (0.0, 0.0, 0.0)),
                                  BC("block_top", (0.0, 0.0, -0.01))), **tol),
               Step("slide", increments=4, bcs=(BC("block_top", (0.04, 0.0, -0.01)),), **tol)))


def test_newton_convergence_order(shared_dir):
    """Elastic block pressed and slid on an elastic foundation (the master deforms).

    With the exact tangent Newton converges quadratically in stick and in slip
    (measured q = 2.1-2.3); CalculiX's tangent (option (a)) needs more iterations.
    """
    mesh = meshes.two_boxes(shared_dir / "boxes.msh")
    exact = run(_sliding_boxes(mesh, "consistent"), write=False).increments
    press, stick, slip = exact[0], exact[1], exact[-1]
    assert stick.slipping == 0 and slip.slipping == slip.active > 0
    # the Newton trace: the press closes the slave nodes in the first iteration (how many
    # change depends on the partition: a node touching at zero clearance reads open or
    # closed by round-off); the state then stays, and the stick increment changes nothing
    # (flat master: no face switches)
    for inc in exact:
        assert (len(inc.status_changes) == len(inc.face_changes) == len(inc.backtracks)
                == inc.iterations == len(inc.residuals) - 1)
        assert inc.status_changes[-1] == 0 and not any(inc.face_changes)
    assert press.status_changes[0] > 0 and not any(press.status_changes[1:])
    assert not any(stick.status_changes)
    for inc in (stick, slip):
        assert observed_order(inc.residuals) >= 1.8, inc.residuals
    approximate = run(_sliding_boxes(mesh, "calculix"), write=False).increments
    assert (sum(i.iterations for i in approximate) > sum(i.iterations for i in exact))
