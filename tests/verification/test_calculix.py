"""Peer comparison with CalculiX CrunchiX (``ccx``, Debian ``calculix-ccx``).

The same 3D problem -- mesh, bodies, laws, parameters, steps and increments --
is solved by dolfinx_friction and by ``ccx`` on a deck written by
:func:`dolfinx_friction.reference.calculix.write_inp`; the reaction sums must agree
within 1 % in every increment.

The problem: an elastic block (first-order hexahedra or tetrahedra) pressed
onto an elastic foundation in 2 increments, then slid over it in 4, with the
linear law at CalculiX's defaults (``K = "calculix"``: 50 E; sigma_inf = E/70000,
c0 = 1e-3) and mu = 0 or 0.3 (``stick_slope = "calculix"``: lambda = E/2).  The
foundation mesh (5 cells per side) and the block mesh (4 per side) are chosen so
that no slave node starts on an edge or a vertex of a master face: there the
choice of the master face is arbitrary (and differs between the codes), and with its tight convergence
controls CalculiX stalls switching faces at the centre node of a 4-on-4 mesh.

What differs (measured with this mesh, dolfinx_friction as of this test's
writing; with the first two made as CalculiX does them in a patched copy, the
reactions agree to about 1e-7 in every increment, hexahedra and tetrahedra,
with and without friction):

* CalculiX computes ``A_p`` from the *deformed* slave faces at every pairing
  (docs/theory.md §2.1), dolfinx_friction from the reference faces.  At
  4 % compression that is 0.07 % of the normal reaction, and up to 1.3 % of
  the tangential reaction while the block sticks (``K_t = lambda A_p``).
* Within an increment our pairing keeps a slave node on its master face up to
  ``interaction.FACE_SLACK`` (5 % of the parametric size) past the face's
  edge; CalculiX moves on to the neighbouring face (its tolerance is
  ``1e-3 sqrt(A_p)``).  On the indented (curved) master this changes the gap
  in the increment where a row of slave nodes crosses an edge: 0.2-0.4 %.
* The initial-overclosure ramp of docs/theory.md §3.4 is not exercised
  (the bodies touch at zero gap).

The worst difference is about 0.4 % of the reaction vector; the test asks for
the issue's 1 %.

Runs serially and under ``mpirun -n 2``: meshes, the deck and ``ccx`` on
rank 0, the reactions broadcast.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from dolfinx_friction.reference import calculix
from dolfinx_friction.reference.meshes import blocks_on_foundation, write_model
from dolfinx_friction.scene.model import BC, Body, Load, Rigid, Scene, Step

comm = MPI.COMM_WORLD
ROOT = comm.rank == 0
HAVE_CCX = comm.bcast(calculix.ccx_available() if ROOT else None, root=0)
needs_ccx = pytest.mark.skipif(
    not HAVE_CCX, reason="CalculiX is not installed (no 'ccx' on the PATH; Debian/Ubuntu: "
    "apt-get install calculix-ccx; or set $CCX)")

E, NU = 1000.0, 0.3
TOL = 0.01  # the 1 %: |R - R_ccx| <= TOL |R_ccx| per group and increment


# --------------------------------------------------------------------------- meshes


def _cube_mesh(path: Path, n: int = 3, tets: bool = False) -> Path:
    """Unit cube, body ``cube``, facet groups ``x0``, ``x1``, ``y0``, ``y1``, ``z0``, ``z1``."""
    import gmsh

    def build():
        box = gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        if tets:  # unstructured: every face number of C3D4 occurs on the boundary
            gmsh.option.setNumber("Mesh.MeshSizeMax", 1.0 / n)
        else:
            for _, c in gmsh.model.getEntities(1):
                gmsh.model.mesh.setTransfiniteCurve(c, n + 1)
            for _, s in gmsh.model.getEntities(2):
                gmsh.model.mesh.setTransfiniteSurface(s)
                gmsh.model.mesh.setRecombine(2, s)
            gmsh.model.mesh.setTransfiniteVolume(box)
        gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [box]), "cube")
        for _, s in gmsh.model.getEntities(2):
            c = gmsh.model.occ.getCenterOfMass(2, s)
            axis = int(np.argmin([min(abs(v), abs(v - 1)) for v in c]))
            name = "xyz"[axis] + ("0" if c[axis] < 0.5 else "1")
            gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, [s]), name)
        gmsh.model.mesh.generate(3)
    return write_model(build, path, comm)


# --------------------------------------------------------------------------- helpers


def _scene_toml(directory: Path, mu: float) -> Path:
    lines = [
        'title = "block pressed and slid on a foundation (CalculiX comparison)"',
        '[mesh]', 'file = "blocks.msh"',
        '[[body]]', 'name = "block"', f'E = {E}', f'nu = {NU}',
        '[[body]]', 'name = "foundation"', f'E = {E}', f'nu = {NU}',
        '[[contact]]', 'slave = "block_bottom"', 'master = "foundation_top"', f'mu = {mu}',
        'K = "calculix"', 'stick_slope = "calculix"',
        '[[step]]', 'name = "press"', 'increments = 2',
        '  [[step.bc]]', '  on = "foundation_bottom"', '  u = [0.0, 0.0, 0.0]',
        '  [[step.bc]]', '  on = "block_top"', '  u = [0.0, 0.0, -0.01]',
        '[[step]]', 'name = "slide"', 'increments = 4',
        '  [[step.bc]]', '  on = "block_top"', '  u = [0.05, 0.0, -0.01]',
        '[output]', 'reactions = ["block_top", "foundation_bottom"]', 'fields = false',
    ]
    path = directory / "scene.toml"
    if ROOT:
        path.write_text("\n".join(lines) + "\n")
    comm.barrier()
    return path


def _run_ccx(scene: Scene, inp: Path) -> tuple[dict, float]:
    """Write the deck and run ccx on rank 0; the reactions and ccx's wall time on every rank."""
    out = None
    if ROOT:
        try:
            calculix.write_inp(scene, inp)
            run = calculix.run_ccx(inp, details=True)
            out = ("ok", run.reactions, run.wall)
        except Exception as e:  # noqa: BLE001 - reported on every rank
            out = ("error", f"{type(e).__name__}: {e}", 0.0)
    status, reactions, wall = comm.bcast(out, root=0)
    if status != "ok":
        raise AssertionError(f"CalculiX run failed: {reactions}")
    return reactions, wall


def _compare(increments, ccx: dict) -> tuple[list[str], float]:
    """Table of the differences per increment and group; the worst ``|dR| / |R_ccx|``."""
    rows = [f"{'step':>4} {'inc':>3} {'group':<18} {'R (ours)':>38} {'R (ccx)':>38} "
            f"{'|dR|/|R|':>9} {'d(dom.)':>9}"]
    worst = 0.0
    for inc in increments:
        theirs = ccx.get(inc.step, {}).get(inc.increment)
        assert theirs is not None, f"no ccx output for step {inc.step}, increment {inc.increment}"
        for group, ours in inc.reactions.items():
            ref = theirs[group]
            rel = float(np.linalg.norm(ours - ref) / np.linalg.norm(ref))
            k = int(np.argmax(np.abs(ref)))
            dom = float(abs(ours[k] - ref[k]) / abs(ref[k]))
            worst = max(worst, rel)
            fmt = lambda v: "[" + ", ".join(f"{x:11.4e}" for x in v) + "]"  # noqa: E731
            rows.append(f"{inc.step:>4} {inc.increment:>3} {group:<18} {fmt(ours):>38} "
                        f"{fmt(ref):>38} {rel:9.2e} {dom:9.2e}")
    return rows, worst


# --------------------------------------------------------------------------- tests


@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("cells, mu", [("hex", 0.0), ("hex", 0.3), ("tet", 0.3)])
def test_block_on_foundation_matches_calculix(shared_dir, cells, mu):
    """Press (2 increments), slide (4): reactions within 1 % of CalculiX's in every increment."""
    from dolfinx_friction.scene.runner import run
    from dolfinx_friction.scene.toml import load_scene

    blocks_on_foundation(shared_dir / "blocks.msh", tets=cells == "tet")
    scene = load_scene(_scene_toml(shared_dir, mu))
    ccx, ccx_wall = _run_ccx(scene, shared_dir / "blocks.inp")
    t0 = time.perf_counter()
    result = run(scene, write=False)
    ours_wall = comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)

    assert [(i.step, i.increment) for i in result.increments] == \
        [(s, k) for s in sorted(ccx) for k in sorted(ccx[s])]
    assert all(i.active == 25 for i in result.increments)
    rows, worst = _compare(result.increments, ccx)
    report = "\n".join(rows + [f"worst |dR|/|R| = {worst:.2e}; wall time: ours {ours_wall:.2f} s "
                               f"({comm.size} rank(s)), ccx {ccx_wall:.2f} s"])
    if ROOT:
        print(f"\n{cells} cells, mu = {mu}\n{report}")
    assert worst <= TOL, report
    if mu > 0.0:  # the block slides at the end: |R_x| ~ mu |R_z| in both codes
        R = result.increments[-1].reactions["block_top"]
        assert 0.25 < abs(R[0] / R[2]) < mu


@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("tets", [False, True], ids=["C3D8", "C3D4"])
def test_face_numbers_and_loads(shared_dir, tets):
    """CalculiX face numbers (``S1``...) of the exported surfaces, checked through loads.

    One side of a cube is fixed and the opposite side loaded by a pressure
    (``*DLOAD`` on the element faces of the surface) or a traction
    (``*CLOAD`` with consistent nodal forces); ``ccx``'s total reaction must be
    the applied force.  A wrong face number puts the load on another face of
    the element and changes the total.
    """
    mesh_path = _cube_mesh(shared_dir / "cube.msh", tets=tets)
    faces_seen: set[int] = set()
    opposite = {"x0": "x1", "x1": "x0", "y0": "y1", "y1": "y0", "z0": "z1", "z1": "z0"}
    for loaded, fixed in opposite.items():
        axis = "xyz".index(loaded[0])
        outward = np.zeros(3)
        outward[axis] = 1.0 if loaded[1] == "1" else -1.0
        traction = (0.3, -0.2, 0.1)
        for load, expected in ((Load(loaded, pressure=2.0), 2.0 * outward),
                               (Load(loaded, traction=traction), -np.asarray(traction))):
            scene = Scene(mesh=mesh_path, bodies=(Body("cube", E, NU),),
                          steps=(Step("load", increments=1, bcs=(BC(fixed, (0.0, 0.0, 0.0)),),
                                      loads=(load,)),))
            ccx, _ = _run_ccx(scene, shared_dir / "cube.inp")
            R = ccx[0][1][fixed]
            # the reaction balances the load: pressure p pushes along -outward (area 1)
            np.testing.assert_allclose(R, expected, atol=1e-9, err_msg=f"load on {loaded}")
        if ROOT:
            mesh = calculix.read_mesh(mesh_path, ["cube"])
            faces_seen |= {f for _, f in mesh.surface(loaded)}
    if ROOT:
        assert faces_seen == set(range(1, 5 if tets else 7))


@pytest.mark.ccx
@needs_ccx
def test_numbers_fit_calculix_fields(shared_dir):
    """CalculiX reads a number from the first 20 characters of its field: a value whose
    repr is longer (a coordinate near zero, a small pressure) must be written shorter, or
    ``7.959123334089213e-05`` is read as 7.959 (it once inverted two elements of a Hertz
    deck at the contact point: "nonpositive jacobian").  Every field of the deck fits, and
    ccx's reaction balances the small pressure."""
    mesh_path = _cube_mesh(shared_dir / "cube.msh")
    p = 7.959123334089213e-05  # repr: 21 characters
    scene = Scene(mesh=mesh_path, bodies=(Body("cube", E, NU),),
                  steps=(Step("load", increments=1, bcs=(BC("x0", (0.0, 0.0, 0.0)),),
                              loads=(Load("x1", pressure=p),)),))
    ccx, _ = _run_ccx(scene, shared_dir / "numbers.inp")
    # (the .dat file prints 7 significant digits)
    np.testing.assert_allclose(ccx[0][1]["x0"], [p, 0.0, 0.0], rtol=1e-6, atol=1e-12)
    if ROOT:
        fields = [f.strip() for line in (shared_dir / "numbers.inp").read_text().splitlines()
                  if not line.startswith("*") for f in line.split(",")]
        assert max(map(len, fields)) <= 20


@pytest.mark.ccx
@needs_ccx
def test_automatic_incrementation(shared_dir):
    """``write_inp(automatic=True)``: ``*STATIC`` with CalculiX's automatic incrementation,
    from the scene's increment size and never above it; ``CcxRun.times`` are the output
    times, and a problem that converges in every increment gives the fixed increments'
    times and reactions (a Neo-Hookean cube stretched 5 % in 2 increments: NLGEOM, so
    CalculiX does increment it)."""
    mesh_path = _cube_mesh(shared_dir / "cube.msh")
    scene = Scene(mesh=mesh_path, bodies=(Body("cube", E, NU, model="neo-hookean"),),
                  steps=(Step("stretch", increments=2,
                              bcs=(BC("x0", (0.0, 0.0, 0.0)), BC("x1", (0.05, None, None)))),))
    if ROOT:
        runs = {}
        for automatic in (False, True):
            inp = shared_dir / f"auto_{automatic}.inp"
            calculix.write_inp(scene, inp, automatic=automatic)
            lines = inp.read_text().splitlines()
            k = next(i for i, ln in enumerate(lines) if ln.startswith("*STATIC"))
            assert lines[k:k + 2] == (["*STATIC", "0.5, 1.0, 5e-05, 0.5"] if automatic
                                      else ["*STATIC, DIRECT", "0.5, 1.0"])
            runs[automatic] = calculix.run_ccx(inp, details=True)
            assert runs[automatic].times == {0: [0.5, 1.0]}
        for k in (1, 2):
            R = runs[False].reactions[0][k]["x0"]
            assert abs(R[0]) > 1.0
            np.testing.assert_allclose(runs[True].reactions[0][k]["x0"], R, rtol=1e-6)


def test_unsupported_scenes_raise(tmp_path):
    """Rigid obstacles have no CalculiX counterpart in the export: a clear error, not a deck."""
    scene = Scene(mesh=tmp_path / "none.msh", bodies=(Body("b", E, NU),),
                  rigids=(Rigid("floor", "plane", point=(0, 0, 0), normal=(0, 0, 1)),),
                  steps=(Step("s"),))
    with pytest.raises(NotImplementedError, match="rigid"):
        calculix.write_inp(scene, tmp_path / "x.inp")
