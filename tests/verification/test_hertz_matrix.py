"""Hertz 2D and 3D, P1 and P2, penalty (the defaults) and augmented Lagrangian, each within
0.5 % of the converged reference (issue #26 item 4); serially and under ``mpirun -n 2``.

The scenes are :mod:`dolfinx_friction.reference.hertz`'s: a quarter disk (plane strain,
quadrilaterals) or a quarter of a lower hemisphere (tetrahedra), R = 10, E = 1000,
nu = 0.3, of geometric order = the displacement degree, pressed onto a rigid plane in one
increment, frictionless, every contact setting at its default but ``method``
(K = 10 E/h; augmented: overclosure below 1e-4 of the slave spacing).

**The reference.**  p0 and a of the elliptic profile fitted to the nodal pressures of the
closed nodes with p > 0.2 max p (``reference.analytic.fit_elliptic``), against Hertz's
half-space p0 and a for the measured load (the top's reaction).  Half-space Hertz is the
converged reference of this finite body within well under the tolerance, measured on
mesh sequences (benchmarks/RESULTS.md, "Verification matrix (issue 26 item 4)"): in 2D
the P1 penalty errors of p0 go -0.25, -0.068, -0.0067 % with h = 0.05, 0.025, 0.0125
(order 1.6, Richardson limit +0.02 %), P2 augmented at h = 0.0125 is +0.07 % / -0.07 %; in 3D P1
augmented at h = 0.035 is +0.14 % / +0.35-0.37 %, the errors falling with h (the a/h = 23
point of "Hertz: speed vs accuracy": 0.012 % / 0.28 %), so a load-dependent correction
of the sphere (not a paraboloid, a/R = 0.072) or of the finite body, if any, is below
about 0.2 %.  The load against the indentation is not compared: the top's displacement
includes the compliance of the whole finite body, which half-space Hertz does not
describe (and 2D Hertz gives no indentation at all).

**The meshes** (contact-zone element size h, ``reference.hertz.MESH_SIZE``) are the
cheapest of the measured sequences whose errors stay within 0.5 % with margin on them and
on the finer meshes.  Measured errors of (p0, a), the same serially and on 2 ranks on one
mesh (the partition changes round-off only), and serial CPU seconds of the run (the
matrix run of benchmarks/RESULTS.md):

=======  =====  ===============================  ===============================
cell     h      penalty (the defaults)           augmented
=======  =====  ===============================  ===============================
2D P1    0.025  -0.068 % / +0.086 %, 0.1 s       +0.140 % / -0.114 %, 0.12 s
2D P2    0.025  -0.027 % / +0.032 %, 0.6 s       +0.071 % / -0.003 %, 0.7 s
3D P1    0.035  -0.206 % / +0.345 %, 7.9 s       +0.102 % / +0.340 %, 9.4 s
3D P2    0.07   -0.689 % / +0.405 %, 17 s (1 %)  -0.340 % / +0.418 %, 28 s (1 %)
=======  =====  ===============================  ===============================

**3D P2 does not reach 0.5 % with margin at a cost a test can carry**, so its two cells
are held to 1 % on h = 0.07.  0.5 % is first met at h = 0.05 (84k dofs, about 100 s CPU
a run): penalty -0.48 % / +0.29 % (no margin), augmented -0.28 % / +0.29 %.  The
sequences (h = 0.15, 0.1, 0.07, 0.05; 2.4, 6.7, 18, 102 s CPU): penalty p0 -2.34, -1.26,
-0.70, -0.48 %, augmented p0 -0.66, -0.56, -0.35, -0.28 %, a +1.25, +1.03, +0.42, +0.29 %.
The penalty's share (penalty - augmented on one mesh: the layer's compliance p/K at the
default K = 10 E/h) falls with h as K grows; P1 meets 0.5 % at the defaults partly by a
cancellation: the same share (-0.31 % at h = 0.035) against a positive discretisation
error (+0.14 %, augmented).  The 3D errors of a are the scatter of the nodal pressures in
the band at the contact edge.  The 3D meshes are gmsh's Delaunay tetrahedra, the same in
every run (the 3D errors above were measured on them; HXT, used before, gave other
tetrahedra in every run, even on one thread, and moved a by up to 0.1 %: +0.415 and
+0.509 % for 3D P2 augmented on two meshes of the same settings).
"""
from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import pytest
from mpi4py import MPI

from dolfinx_friction.reference.hertz import MESH_SIZE, hertz_fit, hertz_mesh, hertz_scene
from dolfinx_friction.scene.runner import PENETRATION_WARNING, run

TOLERANCE = 5e-3
#: the cells held to another bound, and why: the module docstring
LOOSER = {(3, 2, "penalty"): 1e-2, (3, 2, "augmented"): 1e-2}


@pytest.fixture(scope="module")
def mesh_dir():
    """A directory made on rank 0 and known to every rank, for the module's meshes."""
    comm = MPI.COMM_WORLD
    path = comm.bcast(tempfile.mkdtemp(prefix="dfx_hertz_") if comm.rank == 0 else None)
    yield Path(path)
    comm.barrier()
    if comm.rank == 0:
        shutil.rmtree(path, ignore_errors=True)


@pytest.mark.parametrize("method", ["penalty", "augmented"])
@pytest.mark.parametrize("dim,degree", [(2, 1), (2, 2), (3, 1),
                                        pytest.param(3, 2, marks=pytest.mark.slow)])
def test_hertz_within_half_a_percent(dim, degree, method, mesh_dir):
    """Fitted p0 and a within 0.5 % of Hertz's, 3D P2 within 1 % (measured: the module
    docstring's table), no overclosure warning."""
    if (dim, degree) == (3, 2) and MPI.COMM_WORLD.size > 1:
        pytest.skip("3D P2 serially only (45 s a pair): the ranks' answer equals the serial "
                    "one, test_ranks_give_the_serial_answer")
    h = MESH_SIZE[dim, degree]
    mesh = mesh_dir / f"hertz{dim}d_h{h}_order{degree}.msh"
    if not MPI.COMM_WORLD.bcast(mesh.exists()):  # made for the first method, kept for the other
        hertz_mesh(mesh, dim, h, order=degree)
    result = run(hertz_scene(mesh, dim, degree, method), write=False)
    fit = hertz_fit(result, dim)
    tolerance = LOOSER.get((dim, degree, method), TOLERANCE)
    assert abs(fit.err_p0) < tolerance and abs(fit.err_a) < tolerance, fit
    assert max(max(i.penetration.values()) for i in result.increments) < PENETRATION_WARNING


@pytest.mark.skipif(MPI.COMM_WORLD.size == 1, reason="compares ranks with one: run under mpirun")
@pytest.mark.parametrize("dim,degree", [(2, 2), (3, 1)])
def test_ranks_give_the_serial_answer(dim, degree, mesh_dir):
    """Augmented, on the matrix's mesh: load, fitted p0 and a on all ranks are those of a
    serial run of the same mesh (each rank alone) to 1e-9 (measured 1.1e-14 on 2D P2)."""
    h = MESH_SIZE[dim, degree]
    mesh = mesh_dir / f"hertz{dim}d_h{h}_order{degree}.msh"
    if not MPI.COMM_WORLD.bcast(mesh.exists()):
        hertz_mesh(mesh, dim, h, order=degree)
    scene = hertz_scene(mesh, dim, degree, "augmented")
    serial = hertz_fit(run(scene, write=False, comm=MPI.COMM_SELF), dim)
    ranks = hertz_fit(run(scene, write=False), dim)
    assert [ranks.P, ranks.p0_fit, ranks.a_fit] == pytest.approx(
        [serial.P, serial.p0_fit, serial.a_fit], rel=1e-9, abs=0.0)
