"""The contact patch test: what node-to-surface transmits across a flat interface (issue #26).

Two blocks of one material (E = 1000, nu = 0.3) stacked on a flat interface at
height 0.5 (``reference.meshes.stacked``, footprint 1 x 1), the lower one on rollers at
its bottom, both on rollers on their sides x = 0 (and y = 0), a pressure 1 on the upper
block's top, frictionless, every contact setting at its default; the upper block's bottom
is the slave.  The exact solution is a uniform stress: pressure 1 at every slave node.

Node-to-surface passes it only where each slave node's force reaches the master as the
master's consistent load.  What the method gives now (slave nodal pressures, min-max,
serial; slave finer = 4 lower / 6 upper cells per side in 2D, 3 / 4 in 3D):

====================  ==========  ============  ==============
slave faces           matching    slave finer   slave coarser
====================  ==========  ============  ==============
L2 (2D, P1)           1           0.913-1.046   0.853-1.151
L3 (2D, P2)           1           0.862-1.078   0.948-1.143
Q4 (hexahedra, P1)    1           0.832-1.078   0.751-1.126
Q9 (hexahedra, P2)    1           0.948-1.034   0.527-1.628
T3 (tetrahedra, P1)   1           0.696-1.075   0.751-1.234
T6 (tetrahedra, P2)   0.819-1.002 -0.014-1.560  0.706-12.67
====================  ==========  ============  ==============

(1: within 1e-8.)  Against a rigid plane (the upper block alone) quadratic faces pass it
exactly (their forces spread over the faces, theory §2.1).  The recorded bands are
asserted widened by 0.01, so a better method passes too; the force is always transmitted
in full.
"""
from __future__ import annotations

import numpy as np
import pytest

from dolfinx_friction.reference import meshes
from dolfinx_friction.reference.compare import contact_state
from dolfinx_friction.scene.model import BC, Body, ContactPair, Load, Output, Rigid, Scene, Step
from dolfinx_friction.scene.runner import run

# (dim, tets, degree) -> recorded (min, max) for (matching, slave finer, slave coarser);
# None: exact
RECORDED = {
    (2, False, 1): (None, (0.9130, 1.0460), (0.8530, 1.1509)),
    (2, False, 2): (None, (0.8620, 1.0777), (0.9479, 1.1428)),
    (3, False, 1): (None, (0.8324, 1.0775), (0.7509, 1.1255)),
    (3, False, 2): (None, (0.9482, 1.0342), (0.5268, 1.6285)),
    (3, True, 1): (None, (0.6962, 1.0753), (0.7513, 1.2338)),
    (3, True, 2): ((0.8186, 1.0017), (-0.0143, 1.5600), (0.7059, 12.669)),
}
CELLS = {2: {"matching": (6, 6), "slave finer": (4, 6), "slave coarser": (6, 4)},
         3: {"matching": (4, 4), "slave finer": (3, 4), "slave coarser": (4, 3)}}


def _pressures(shared_dir, dim: int, tets: bool, degree: int, cells: tuple[int, int],
               rigid: bool = False) -> np.ndarray:
    """The slave nodal pressures (all ranks) under the pressure 1, and the check that the
    slave nodes carry the whole load."""
    mesh = meshes.stacked(shared_dir / "stack.msh", *cells, dim=dim, tets=tets)

    def roller(group: str, axis: int) -> BC:
        return BC(group, tuple(0.0 if i == axis else None for i in range(dim)))
    bcs = [roller("upper_x0", 0)] + ([roller("upper_y0", 1)] if dim == 3 else [])
    if rigid:  # the upper block alone on a rigid plane where the lower block's top is
        bodies = (Body("upper", 1000.0, 0.3, degree=degree),)
        obstacles = (Rigid("floor", "plane", point=(0.0,) * (dim - 1) + (0.5,),
                           normal=(0.0,) * (dim - 1) + (1.0,)),)
        master = "floor"
    else:
        bodies = tuple(Body(name, 1000.0, 0.3, degree=degree) for name in ("lower", "upper"))
        obstacles, master = (), "lower_top"
        bcs += [roller("lower_bottom", dim - 1), roller("lower_x0", 0)]
        bcs += [roller("lower_y0", 1)] if dim == 3 else []
    scene = Scene(mesh=mesh, bodies=bodies, rigids=obstacles,
                  contacts=(ContactPair("upper_bottom", master),),
                  steps=(Step("press", bcs=tuple(bcs),
                              loads=(Load("upper_top", pressure=1.0),)),),
                  output=Output(fields=False, contact_table=False))
    st = contact_state(run(scene, write=False))
    assert st["normal_force"].sum() == pytest.approx(1.0, rel=1e-6)  # footprint 1
    return st["pressure"]


@pytest.mark.parametrize("case", ["matching", "slave finer", "slave coarser"])
@pytest.mark.parametrize("dim, tets, degree", list(RECORDED))
def test_patch_between_two_blocks(shared_dir, dim, tets, degree, case):
    p = _pressures(shared_dir, dim, tets, degree, CELLS[dim][case])
    print(f"\n{dim}D {'tets' if tets else 'quads/hexes'} P{degree}, {case}: slave pressures "
          f"{p.min():.4f} - {p.max():.4f}")
    recorded = RECORDED[(dim, tets, degree)][list(CELLS[dim]).index(case)]
    if recorded is None:
        np.testing.assert_allclose(p, 1.0, atol=1e-8)
    else:
        assert recorded[0] - 0.01 <= p.min() and p.max() <= recorded[1] + 0.01


@pytest.mark.parametrize("dim, tets", [(2, False), (3, False), (3, True)])
def test_patch_on_a_rigid_plane_with_quadratic_faces(shared_dir, dim, tets):
    """L3, Q9, T6 slave faces on a rigid plane: pressure 1 at every node within 1e-8
    (CalculiX's weights on T6 faces: 0.89-1.0015)."""
    p = _pressures(shared_dir, dim, tets, 2, CELLS[dim]["matching"], rigid=True)
    np.testing.assert_allclose(p, 1.0, atol=1e-8)
