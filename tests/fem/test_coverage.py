"""Every cell type, degree, plane model and obstacle shape runs end to end and balances.

A body pressed onto a rigid obstacle: the obstacle's force equals minus the reaction of
the pressed group (global equilibrium through the contact elements), to solver tolerance.
"""
from __future__ import annotations

import numpy as np
import pytest

from dolfinx_friction.scene.runner import run
from dolfinx_friction.scene.model import BC, Body, ContactPair, Rigid, Scene, Step
from dolfinx_friction.reference import meshes


def _press(mesh, body: Body, rigid: Rigid, u: tuple, mu: float = 0.2) -> Scene:
    d = len(u)
    slide = (0.01,) + (0.0,) * (d - 2) + (u[-1],)
    return Scene(mesh=mesh, bodies=(body,), rigids=(rigid,),
                 contacts=(ContactPair("bottom", rigid.name, mu=mu),),
                 steps=(Step("press", increments=2, bcs=(BC("top", u),)),
                        Step("slide", increments=2, bcs=(BC("top", slide),))))


def _balanced(result, rigid: str) -> None:
    last = result.increments[-1]
    assert last.active > 0
    np.testing.assert_allclose(last.rigid_f[rigid], -last.reactions["top"], rtol=1e-7,
                               atol=1e-9 * np.abs(last.reactions["top"]).max())


@pytest.mark.parametrize("quads, order, degree, plane", [
    (True, 1, 1, "strain"), (False, 1, 1, "stress"), (True, 2, 2, "strain"),
    (False, 2, 2, "stress"), (True, 1, 2, "strain")])
def test_2d_cells_degrees_and_plane_models(shared_dir, quads, order, degree, plane):
    mesh = meshes.rectangle_2d(shared_dir / "rect.msh", n=(8, 2), quads=quads, order=order)
    body = Body("block", 1000.0, 0.3, degree=degree, plane=plane, thickness=2.0)
    floor = Rigid("floor", "plane", point=(0.0, 0.0), normal=(0.0, 1.0))
    _balanced(run(_press(mesh, body, floor, (0.0, -0.002)), write=False), "floor")


@pytest.mark.parametrize("tets, degree", [(False, 1), (True, 1), (False, 2), (True, 2)])
def test_3d_cells_and_degrees(shared_dir, tets, degree):
    mesh = meshes.block_3d(shared_dir / "block.msh", n=(3, 3, 2), tets=tets)
    body = Body("block", 1000.0, 0.3, degree=degree)
    floor = Rigid("floor", "plane", point=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0))
    _balanced(run(_press(mesh, body, floor, (0.0, 0.0, -0.002)), write=False), "floor")


@pytest.mark.parametrize("rigid", [
    Rigid("ball", "sphere", center=(0.5, 0.5, -1.0), radius=1.0),
    Rigid("roller", "cylinder", point=(0.0, 0.5, -1.0), axis=(1.0, 0.0, 0.0), radius=1.0)])
def test_curved_rigid_obstacles_3d(shared_dir, rigid):
    mesh = meshes.block_3d(shared_dir / "block.msh", n=(6, 6, 2))
    body = Body("block", 1000.0, 0.3)
    _balanced(run(_press(mesh, body, rigid, (0.0, 0.0, -0.01)), write=False), rigid.name)


def test_rigid_circle_2d(shared_dir):
    mesh = meshes.rectangle_2d(shared_dir / "rect.msh", n=(16, 2))
    body = Body("block", 1000.0, 0.3)
    disk = Rigid("disk", "sphere", center=(0.5, -1.0), radius=1.0)
    _balanced(run(_press(mesh, body, disk, (0.0, -0.01)), write=False), "disk")
