"""Hertz contact on a rigid plane, the verification matrix of issue #26 item 4: a quarter
disk (2D plane strain, cylinder) or a quarter of a lower hemisphere (3D, sphere), R = 10,
E = 1000, nu = 0.3, pressed onto the rigid plane through the first contact point in one
increment, frictionless, every contact setting at its default but ``method``; and its
measures, Hertz's p0 and a fitted to the nodal pressures against the closed form for the
measured load.  Shared by ``tests/verification/test_hertz_matrix.py`` and
``benchmarks/bench_hertz_matrix.py``."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from mpi4py import MPI

from dolfinx_friction.reference import meshes
from dolfinx_friction.reference.analytic import (effective_modulus, fit_elliptic, hertz_line,
                                                 hertz_sphere)
from dolfinx_friction.reference.compare import contact_state
from dolfinx_friction.scene.model import BC, Body, ContactPair, Output, Rigid, Scene, Step

__all__ = ["E", "NU", "R", "DEPTH", "REFINE", "MESH_SIZE", "hertz_mesh", "hertz_scene",
           "HertzFit", "hertz_fit"]

E, NU, R = 1000.0, 0.3, 10.0
#: approach of the top per dimension: Hertz half-width a = 0.46 (2D), radius 0.72 (3D)
DEPTH = {2: 0.04, 3: 0.05}
#: radius of the refined zone around the first contact point (about 2 a in 2D, 1.25 a in 3D)
REFINE = {2: 1.0, 3: 0.9}
#: the verification matrix's contact-zone element size per (dimension, degree): the
#: cheapest measured mesh within 0.5 % with margin, 3D P2 penalty excepted
#: (tests/verification/test_hertz_matrix.py says why)
MESH_SIZE = {(2, 1): 0.025, (2, 2): 0.025, (3, 1): 0.035, (3, 2): 0.07}
_TOP = {2: "cylinder_top", 3: "sphere_top"}


def hertz_mesh(path: Path, dim: int, h: float, order: int,
               comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    """The body's mesh (:func:`~dolfinx_friction.reference.meshes.quarter_disk` or
    :func:`~dolfinx_friction.reference.meshes.quarter_sphere`), element size ``h`` within
    :data:`REFINE` of the first contact point, geometric ``order`` 1 or 2."""
    build = meshes.quarter_disk if dim == 2 else meshes.quarter_sphere
    return build(path, R=R, h_contact=h, refine_radius=REFINE[dim], order=order, comm=comm)


def hertz_scene(mesh: Path, dim: int, degree: int, method: str = "penalty") -> Scene:
    """The body of ``mesh`` (displacement degree ``degree``) pressed by :data:`DEPTH` onto
    the rigid plane, symmetry on the cut planes; contact ``method`` "penalty" or
    "augmented"; the reaction of the top is recorded."""
    if dim == 2:
        body, surface, bcs = "cylinder", "cylinder_surface", (
            BC("cylinder_symmetry", (0.0, None)), BC("cylinder_top", (0.0, -DEPTH[2])))
        floor = Rigid("floor", "plane", point=(0.0, 0.0), normal=(0.0, 1.0))
    else:
        body, surface, bcs = "sphere", "sphere_surface", (
            BC("sphere_symmetry_x", (0.0, None, None)),
            BC("sphere_symmetry_y", (None, 0.0, None)),
            BC("sphere_top", (0.0, 0.0, -DEPTH[3])))
        floor = Rigid("floor", "plane", point=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0))
    return Scene(mesh=mesh, bodies=(Body(body, E, NU, degree=degree),), rigids=(floor,),
                 contacts=(ContactPair(surface, "floor", method=method),),
                 steps=(Step("press", bcs=bcs),),
                 output=Output(fields=False, contact_table=False, reactions=(_TOP[dim],)))


@dataclass(frozen=True)
class HertzFit:
    """Load ``P`` of the whole cylinder (per unit length) or sphere, Hertz's ``a`` and
    ``p0`` for it, and those of the elliptic profile fitted to the nodal pressures."""

    P: float
    a: float
    p0: float
    a_fit: float
    p0_fit: float

    @property
    def err_a(self) -> float:
        """``a_fit / a - 1``."""
        return self.a_fit / self.a - 1.0

    @property
    def err_p0(self) -> float:
        """``p0_fit / p0 - 1``."""
        return self.p0_fit / self.p0 - 1.0


def hertz_fit(result, dim: int) -> HertzFit:
    """p0 and a of ``p^2 = p0^2 (1 - r^2/a^2)`` fitted by least squares to the nodal
    pressures ``F_N / A`` of the closed slave nodes with p > 0.2 max p (``r``: reference
    distance from the axis), and Hertz's half-space values for the load of the last
    increment (the top's reaction x 2 in 2D, x 4 in 3D).  The same on every rank."""
    F = abs(result.increments[-1].reactions[_TOP[dim]][dim - 1])
    st = contact_state(result)
    closed = st["status"] != 0
    if dim == 2:
        P = 2.0 * F
        a, p0 = hertz_line(P, R, effective_modulus(E, NU))
        r = np.abs(st["X"][closed, 0])
    else:
        P = 4.0 * F
        a, p0, _ = hertz_sphere(P, R, effective_modulus(E, NU))
        r = np.linalg.norm(st["X"][closed, :2], axis=1)
    a_fit, p0_fit = fit_elliptic(r, st["pressure"][closed])
    return HertzFit(P, a, p0, a_fit, p0_fit)
