"""Contact pressures on quadratic (P2) slave faces against Hertz, pointwise (issue #26).

A quarter disk (2D, 3-node edges) and a quarter of a lower hemisphere (3D, T6 faces),
R = 10, E = 1000, nu = 0.3, of second-order geometry (mid-side nodes on the circle or
sphere; theory §2.1 explains why not first-order), pressed onto a rigid plane in one
increment, frictionless, every contact setting at its default; and onto an elastic block
of the same material, P2 too (Hertz with E* of the two bodies; the default distribution
there is the mortar one, theory §2.1).  The nodal pressures
``F_N / A_k`` of every slave node within 0.8 a are compared with Hertz's profile for the
measured load.  Each bound is the issue's target; the measured values (serial, this mesh)
are in the tests' docstrings.  Coarser meshes than the demos' (2D: a/h = 18; 3D:
a/h = 8, 190 nodes within 0.8 a) keep the tests short.
"""
from __future__ import annotations

import numpy as np
import pytest
from mpi4py import MPI

from dolfinx_friction.reference import meshes
from dolfinx_friction.reference.analytic import effective_modulus, hertz_line, hertz_sphere
from dolfinx_friction.reference.compare import contact_state
from dolfinx_friction.scene.model import BC, Body, ContactPair, Output, Rigid, Scene, Step
from dolfinx_friction.scene.runner import FACETING_WARNING, PENETRATION_WARNING, run

E, NU, R = 1000.0, 0.3, 10.0


def _pressed(mesh, dim: int, depth: float, block: bool = False, distribution=None,
             degree: int = 2, faceting: bool = False):
    """Run the body of ``mesh`` with P2 onto the rigid plane (``block``: onto the elastic
    block of the mesh, P2 as well, with ``distribution``); the deviations of the nodal
    pressures within 0.8 a from Hertz (relative to p0) ordered by the distance r from the
    axis, r, and the largest overclosure relative to the slave spacing (``faceting``: and
    the pair's chord depth and its ratio to the overclosure at the end)."""
    if dim == 2:
        body, surface, top, bcs = "cylinder", "cylinder_surface", "cylinder_top", (
            BC("cylinder_symmetry", (0.0, None)), BC("cylinder_top", (0.0, -depth)))
        floor = Rigid("floor", "plane", point=(0.0, 0.0), normal=(0.0, 1.0))
        under = (BC("block_symmetry", (0.0, None)), BC("block_bottom", (0.0, 0.0)))
    else:
        body, surface, top, bcs = "sphere", "sphere_surface", "sphere_top", (
            BC("sphere_symmetry_x", (0.0, None, None)), BC("sphere_symmetry_y", (None, 0.0, None)),
            BC("sphere_top", (0.0, 0.0, -depth)))
        floor = Rigid("floor", "plane", point=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0))
        under = (BC("block_symmetry_x", (0.0, None, None)),
                 BC("block_symmetry_y", (None, 0.0, None)), BC("block_bottom", (0.0,) * 3))
    bodies = (Body(body, E, NU, degree=degree),) + ((Body("block", E, NU, degree=degree),)
                                                    if block else ())
    scene = Scene(mesh=mesh, bodies=bodies, rigids=() if block else (floor,),
                  contacts=(ContactPair(surface, "block_top" if block else "floor",
                                        distribution=distribution),),
                  steps=(Step("press", bcs=bcs + (under if block else ())),),
                  output=Output(fields=False, contact_table=False, reactions=(top,)))
    result = run(scene, write=False)
    F = abs(result.increments[-1].reactions[top][dim - 1])
    st = contact_state(result)
    E_star = effective_modulus(E, NU, E, NU) if block else effective_modulus(E, NU)
    if dim == 2:
        a, p0 = hertz_line(2.0 * F, R, E_star)
        r = np.abs(st["X"][:, 0])
    else:
        a, p0, _ = hertz_sphere(4.0 * F, R, E_star)
        r = np.linalg.norm(st["X"][:, :2], axis=1)
    inner = np.flatnonzero(r < 0.8 * a)
    inner = inner[np.argsort(r[inner])]
    hertz = p0 * np.sqrt(1.0 - (r[inner] / a) ** 2)
    penetration = max(max(i.penetration.values()) for i in result.increments)
    deviation = (st["pressure"][inner] - hertz) / p0
    if faceting:
        pair, = result.problem.pairs.values()
        return (deviation, r[inner], penetration) + pair.faceting()
    return deviation, r[inner], penetration


def test_hertz_cylinder_p2_without_zigzag(shared_dir):
    """3-node edges: every node within 0.8 a within 0.2 % of p0 (measured 0.06 %, centre
    -0.008 %; CalculiX's 1/6, 2/3, 1/6 weights: 0.10 %), and no vertex/mid-side zig-zag:
    the largest second difference of the nodal pressures minus Hertz below 0.2 % of p0
    (measured 0.065 %; CalculiX's weights 0.16 %); overclosure 0.5 % of the spacing."""
    mesh = meshes.quarter_disk(shared_dir / "disk.msh", R=R, h_contact=0.025,
                               refine_radius=1.0, order=2)
    deviation, r, penetration = _pressed(mesh, 2, depth=0.04)
    assert len(r) >= 25 and r[0] == pytest.approx(0.0, abs=1e-12)
    assert np.abs(deviation).max() < 2e-3
    assert np.abs(np.diff(deviation, 2)).max() < 2e-3
    assert penetration < PENETRATION_WARNING


def test_hertz_sphere_p2_pointwise(shared_dir):
    """T6 faces: centre node within 2 % of p0 (measured -0.8 %; CalculiX's 1/999 weights:
    -8.2 % on an earlier mesh of gmsh's HXT), every node within 0.8 a within 5 % (measured
    3.5 %; CalculiX's weights 11.2 %), no overclosure warning (measured 2.3 % of the slave
    spacing; CalculiX's weights 15.5 %)."""
    mesh = meshes.quarter_sphere(shared_dir / "sphere.msh", R=R, h_contact=0.15,
                                 refine_radius=1.5, order=2)
    deviation, r, penetration = _pressed(mesh, 3, depth=0.15)
    assert len(r) >= 150 and r[0] == pytest.approx(0.0, abs=1e-12)
    assert abs(deviation[0]) < 0.02
    assert np.abs(deviation).max() < 0.05
    assert penetration < PENETRATION_WARNING


def test_hertz_cylinder_p2_on_an_elastic_block(shared_dir):
    """3-node edges on a block of the same material (20 x 10, P2, the same sizes, non-matching),
    top pressed by 0.08, the default distribution (mortar for P2 on a deformable master):
    every node within 0.8 a within 1.2 % of Hertz's p0 for E* of the two bodies (measured
    0.93 %, at the centre; nodal distribution: 1.49 %), no zig-zag: the largest second
    difference below the issue's 0.2 % (measured 0.033 %; nodal 2.7 %); overclosure 0.4 %
    of the spacing."""
    mesh = meshes.quarter_disk(shared_dir / "disk_block.msh", R=R, h_contact=0.025,
                               refine_radius=1.5, order=2, block=(20.0, 10.0))
    deviation, r, penetration = _pressed(mesh, 2, depth=0.08, block=True)
    assert len(r) >= 40 and r[0] == pytest.approx(0.0, abs=1e-12)
    assert np.abs(deviation).max() < 1.2e-2
    assert np.abs(np.diff(deviation, 2)).max() < 2e-3
    assert penetration < PENETRATION_WARNING


def test_hertz_sphere_p2_on_an_elastic_block(shared_dir):
    """T6 faces on a quarter block of the same material (6 x 6 x 3, P2, the same sizes,
    non-matching), the sphere's top pressed by 0.2, the default distribution (mortar for
    P2 on a deformable master): the centre node within 4 % of Hertz's p0 for E* of the two
    bodies and every node within 0.8 a within 5 % (measured +1.4 % / 2.9 % on gmsh 4.8's
    mesh, +3.2 % / 3.9 % on gmsh 4.13's of trixie and sid; the nodal distribution +357 %,
    its overclosure 56 % of the spacing); no overclosure warning (2.5 %).  The bounds are
    those of the worse mesh.  On 2 ranks in Debian sid 1 solve in 3-10 once converged the
    press in one increment on pairings frozen 21 iterations before (a node 146 % of p0
    off); the postcondition now cuts such an increment back (2 of 10 solves there, each
    then right: NodeToSurface.stale_pairing)."""
    mesh = meshes.quarter_sphere(shared_dir / "sphere_block.msh", R=R, h_contact=0.25,
                                 refine_radius=1.5, order=2, block=(6.0, 3.0))
    deviation, r, penetration = _pressed(mesh, 3, depth=0.2, block=True)
    assert len(r) >= 100 and r[0] == pytest.approx(0.0, abs=1e-12)
    assert abs(deviation[0]) < 0.04
    assert np.abs(deviation).max() < 0.05
    assert penetration < PENETRATION_WARNING


def test_quadratic_faces_on_first_order_geometry_warn(shared_dir, caplog):
    """P2 on a sphere meshed with first-order geometry (h = 0.2): the mid-side nodes lie on
    chords, h^2/8R = 5e-4 inside the sphere (measured 6.4e-4 on the closed nodes' longest
    edges, 38 % of the overclosure): one warning naming the pair and the fix.  The same
    mesh with P1, and the second-order mesh with P2, have no mid-side nodes off the
    surface: no warning."""
    first = meshes.quarter_sphere(shared_dir / "sphere_first.msh", R=R, h_contact=0.2,
                                  refine_radius=1.5, order=1)
    second = meshes.quarter_sphere(shared_dir / "sphere_second.msh", R=R, h_contact=0.2,
                                   refine_radius=1.5, order=2)
    for mesh, degree, warns in ((first, 2, True), (first, 1, False), (second, 2, False)):
        caplog.clear()
        with caplog.at_level("WARNING", logger="dolfinx_friction.scene.runner"):
            _, _, _, depth, ratio = _pressed(mesh, 3, depth=0.15, degree=degree,
                                             faceting=True)
        faceted = [r.getMessage() for r in caplog.records if "first-order" in r.getMessage()]
        if warns:
            assert 0.25 * 0.2 ** 2 / (8 * R) < depth < 2.0 * 0.2 ** 2 / (8 * R)
            assert ratio > FACETING_WARNING
            if MPI.COMM_WORLD.rank == 0:
                assert len(faceted) == 1 and "sphere_surface->floor" in faceted[0]
                assert "Mesh.ElementOrder = 2" in faceted[0]
        else:
            assert (depth, ratio) == (0.0, 0.0) and not faceted
