"""Small parametric scenes of the stability maps, and one run reduced to a table row.

Three families, all small enough for a sweep of hundreds of runs:

* ``block`` -- the sliding block in 2D plane strain: an elastic block (1 x 0.5) pressed
  onto an elastic foundation and slid along it.  Every geometric knob of the maps lives
  here: slave and master mesh sizes, the slide per increment (in master faces), the end
  of the master surface (overhang), the initial gap or penetration.
* ``hertz`` -- the Hertz cylinder demo (``demos/hertz_cylinder.py``: its ``build_mesh``
  and its scene file), at a coarse resolution.
* ``ironing`` -- the ironing demo (``demos/ironing.py``: a rigid circle pressed into a
  soft block and dragged along it, mu = 0.3), coarse; without the demo, a stiff elastic
  half-cylinder punch (slave) pressed into an elastic strip and slid (built here).
* ``block3d`` -- the 3D sliding block demo (``demos/sliding_block.py``), coarse.
* ``groove`` -- a convex slave tip pressed into a concave V-groove: the face chattering
  that the pairing freeze exists for.

:func:`run_case` runs one case dictionary in memory and returns its outcome (converged /
converged after cutbacks / failed / error), iteration counts, the penetration ratio and
an accuracy measure; it never raises.  Meshes are cached in ``$STABILITY_WORK`` (default
``/tmp/dolfinx_friction_stability``), never written into the repository.
"""
from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import hashlib  # noqa: E402
import importlib.util  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import types  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
DEMOS = ROOT / "demos"
WORK = Path(os.environ.get("STABILITY_WORK", "/tmp/dolfinx_friction_stability"))
for _p in (str(ROOT),):
    if _p not in sys.path:
        sys.path.insert(0, _p)

E = 1000.0
NU = 0.3

# --------------------------------------------------------------------------- block (2D)
BLOCK_W = 1.0  # the block of meshes.block_on_foundation: 1 x 0.5 on a foundation 0.5 deep
PRESS = 0.01  # block top pushed down by 0.01 (2 % of its height)
SLIDE = 0.5  # then slid by half the block width (4 slave faces)


def build_block(path: Path, **params) -> Path:
    """:func:`dolfinx_friction.reference.meshes.block_on_foundation` (serially)."""
    from mpi4py import MPI

    from dolfinx_friction.reference import meshes
    return meshes.block_on_foundation(path, comm=MPI.COMM_SELF, **params)


# ------------------------------------------------------------------------ ironing (2D)
IRON_R = 1.0
IRON_LENGTH, IRON_DEPTH = 4.0, 1.0
IRON_X0 = 1.0  # punch centre at the start
IRON_E_PUNCH = 10.0 * E
IRON_PRESS = 0.03
IRON_SLIDE = 1.0


def build_ironing(path: Path, h_slave: float = 0.1, ratio: float = 1.0) -> Path:
    """Half-disc punch (radius 1, centre (1, 1), touching y = 0 at x = 1) over a strip
    [0, 4] x [-1, 0].  Punch: quadrilaterals of size ``h_slave`` near its lowest point
    (growing to 0.25 at the top); strip: structured, top spacing ``h_slave / ratio``.
    Groups: bodies ``punch``, ``strip``; edges ``punch_surface``, ``punch_top``,
    ``strip_top``, ``strip_bottom``.
    """
    import gmsh

    from dolfinx_friction.reference import meshes
    R, X0 = IRON_R, IRON_X0
    h_m = h_slave / ratio
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("ironing")
        geo = gmsh.model.geo
        c = geo.addPoint(X0, R, 0)
        left, low, right = (geo.addPoint(X0 - R, R, 0), geo.addPoint(X0, 0, 0),
                            geo.addPoint(X0 + R, R, 0))
        a1, a2 = geo.addCircleArc(left, c, low), geo.addCircleArc(low, c, right)
        top = geo.addLine(right, left)
        punch = geo.addPlaneSurface([geo.addCurveLoop([a1, a2, top])])
        geo.synchronize()
        strip, sl = meshes.structured_rectangle(0.0, -IRON_DEPTH, IRON_LENGTH, IRON_DEPTH,
                                                max(1, round(IRON_LENGTH / h_m)),
                                                max(4, round(IRON_DEPTH / 0.1)))
        f = gmsh.model.mesh.field
        dist = f.add("Distance")
        f.setNumbers(dist, "CurvesList", [a1, a2])
        thr = f.add("Threshold")
        f.setNumber(thr, "InField", dist)
        f.setNumber(thr, "SizeMin", h_slave)
        f.setNumber(thr, "SizeMax", 0.25)
        f.setNumber(thr, "DistMin", 0.05)
        f.setNumber(thr, "DistMax", 0.8)
        restrict = f.add("Restrict")
        f.setNumber(restrict, "InField", thr)
        f.setNumbers(restrict, "SurfacesList", [punch])
        f.setNumbers(restrict, "CurvesList", [a1, a2, top])
        f.setAsBackgroundMesh(restrict)
        for key, value in (("Mesh.MeshSizeExtendFromBoundary", 0), ("Mesh.MeshSizeFromPoints", 0),
                           ("Mesh.MeshSizeFromCurvature", 0), ("Mesh.Algorithm", 6),
                           ("Mesh.RecombinationAlgorithm", 1)):
            gmsh.option.setNumber(key, value)
        gmsh.model.mesh.setRecombine(2, punch)
        meshes.group(2, [punch], "punch")
        meshes.group(2, [strip], "strip")
        meshes.group(1, [a1, a2], "punch_surface")
        meshes.group(1, [top], "punch_top")
        meshes.group(1, [sl["top"]], "strip_top")
        meshes.group(1, [sl["bottom"]], "strip_bottom")
        gmsh.model.mesh.generate(2)
        types_ = gmsh.model.mesh.getElementTypes(2)
        if len(types_) != 1:
            raise RuntimeError(f"mixed 2D element types {types_}")
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path


# --------------------------------------------------------------------------- groove (2D)
def build_groove(path: Path, h: float = 0.0625, slope_master: float = 0.1,
                 slope_slave: float = 0.2) -> Path:
    """:func:`dolfinx_friction.reference.meshes.tip_in_groove` (serially)."""
    from mpi4py import MPI

    from dolfinx_friction.reference import meshes
    return meshes.tip_in_groove(path, h, slope_master, slope_slave, comm=MPI.COMM_SELF)


# ----------------------------------------------------------------------------- demos
def demo_module(name: str):
    """``demos/<name>.py`` imported without its pyvista helper (None if absent)."""
    path = DEMOS / f"{name}.py"
    if not path.exists():
        return None
    if "_common" not in sys.modules:
        stub = types.ModuleType("_common")
        stub.HERE = DEMOS
        sys.modules["_common"] = stub
    spec = importlib.util.spec_from_file_location(f"stability_demo_{name}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def cached_mesh(kind: str, builder, **params) -> Path:
    """Build a mesh once per parameter set (atomic rename: safe with parallel workers)."""
    WORK.mkdir(parents=True, exist_ok=True)
    key = hashlib.sha1(json.dumps([kind, params], sort_keys=True).encode()).hexdigest()[:12]
    path = WORK / f"{kind}_{key}.msh"
    if not path.exists():
        from dolfinx_friction.io.files import atomic_path
        with atomic_path(path) as tmp:
            builder(tmp, **params)
    return path


# ---------------------------------------------------------------------------- scenes
def _contact(case: dict, slave: str, master: str, h: float, E_slave: float, mu: float):
    """The contact pair of a case: K and the stick slope given as multiples of E_slave / h;
    without ``lam`` the stick slope of the maps, CalculiX's E/2 (the default before
    scene-format version 2); ``contact_method``: ``"penalty"`` (default) or
    ``"augmented"`` (augmented Lagrangian; ``augmented_tolerance``, default 1e-4 of the
    spacing)."""
    from dolfinx_friction.scene.model import ContactPair
    k = case.get("k", 10.0)
    lam = case.get("lam")
    pi = case.get("pairing", 8)
    return ContactPair(slave, master, K=k * E_slave / h, mu=case.get("mu", mu),
                       stick_slope="calculix" if lam is None else lam * E_slave / h,
                       tangent=case.get("tangent", "consistent"),
                       pairing_iterations=1000 if pi in (None, "never", 0) else int(pi),
                       method=case.get("contact_method", "penalty"),
                       augmented_tolerance=case.get("augmented_tolerance", 1e-4))


def _step_kw(case: dict) -> dict:
    return dict(max_cutbacks=case.get("max_cutbacks", 5),
                max_iterations=case.get("max_iterations", 30),
                line_search=bool(case.get("line_search", False)))


def block_scene(case: dict):
    """The 2D sliding block of ``case`` (see :func:`build_block`).

    Case keys: ``n_slave`` (8), ``ratio`` (h_s/h_m, 1), ``gap`` (initial clearance in slave
    spacings; negative = initial penetration), ``overhang`` (how far the block ends past the
    end of the master surface, in block widths), ``slide_faces`` (slide per increment in
    master faces; else ``increments``), ``press_increments`` (1), ``k``, ``lam``, ``mu``
    (0.3), ``tangent``, ``pairing``, ``line_search``, ``max_cutbacks``.
    """
    from dolfinx_friction.scene.model import BC, Body, Scene, Step
    n = int(case.get("n_slave", 8))
    ratio = float(case.get("ratio", 1.0))
    h_s = BLOCK_W / n
    h_m = h_s / ratio
    gap = float(case.get("gap", 0.0)) * h_s
    slide = float(case.get("slide", SLIDE))
    x_end = BLOCK_W + slide - float(case.get("overhang", -0.5)) * BLOCK_W
    mesh = cached_mesh("block", build_block, n_slave=n, ratio=ratio, y0=round(gap, 12),
                       x_end=round(x_end, 12))
    if "slide_faces" in case:
        increments = max(1, round(slide / (case["slide_faces"] * h_m)))
    else:
        increments = int(case.get("increments", 10))
    # an initial gap is closed first; an initial penetration is ramped out over the press
    # step and then acts in full (docs/theory.md §3.4), so the top moves by PRESS + gap
    # in both cases: every gap ends in the zero-gap state
    press = PRESS + gap
    kw = _step_kw(case)
    steps = [Step("press", increments=int(case.get("press_increments", 1)),
                  bcs=(BC("foundation_bottom", (0.0, 0.0)), BC("block_top", (0.0, -press))), **kw)]
    if slide > 0:
        steps.append(Step("slide", increments=increments,
                          bcs=(BC("block_top", (slide, -press)),), **kw))
    scene = Scene(mesh=mesh, bodies=(Body("block", E, NU), Body("foundation", E, NU)),
                  contacts=(_contact(case, "block_bottom", "foundation_top", h_s, E, 0.3),),
                  steps=tuple(steps))
    return scene, dict(h=h_s, reaction="block_top", increments=increments)


def hertz_scene(case: dict):
    """The Hertz cylinder demo, coarse: ``h`` (slave size at the contact, 0.2), ``ratio``
    (h_slave / h_master, 0.5 as in the demo), ``increments`` (4), ``k``, ``mu`` (0), ...

    ``swap``: the block top is the slave and the (coarser) cylinder the master -- a
    faceted convex master, the textbook source of face-to-face chattering.
    """
    from dolfinx_friction.scene.toml import load_scene
    demo = demo_module("hertz_cylinder")
    h = float(case.get("h", 0.2))
    ratio = float(case.get("ratio", 0.5))
    swap = bool(case.get("swap", False))
    # build_mesh: cylinder size h_contact, block size master_ratio * h_contact
    h_cyl, h_block = (h / ratio, h) if swap else (h, h / ratio)
    mesh = cached_mesh("hertz", demo.build_mesh, h_contact=h_cyl, h_far=2.5,
                       master_ratio=h_block / h_cyl, refine_radius=2.5)
    base = load_scene(DEMOS / "hertz_cylinder.toml")
    c = base.contacts[0]
    slave, master = (c.master, c.slave) if swap else (c.slave, c.master)
    E_s = base.body("block" if swap else "cylinder").E
    pair = _contact(case, slave, master, h, E_s, 0.0)
    steps = tuple(replace(s, increments=int(case.get("increments", s.increments)),
                          **_step_kw(case)) for s in base.steps)
    scene = replace(base, mesh=mesh, contacts=(pair,), steps=steps)
    return scene, dict(h=h, reaction="cylinder_top", increments=steps[0].increments)


def ironing_scene(case: dict):
    """Ironing: ``demos/ironing.py`` if present (its ``build_mesh`` and ``ironing.toml``:
    a die pressed into a soft block, slave = block top, then dragged along it), coarse;
    otherwise the deformable punch of :func:`build_ironing`.

    The demo's die is driven either as a ``[[rigid]]`` obstacle or through a bc on its
    top face; both are handled.  Keys: ``nx`` (block elements along its length 20,
    default 40: h = 0.5), ``ny`` (8), ``n_arc`` (elements on the die's arc if the demo has
    them, 16), ``travel`` (drag distance, 4; the demo's is longer), ``slide_faces`` (drag per
    increment in master faces -- the die's arc elements, or slave spacings for a rigid
    die) or ``increments``, ``press_increments`` (as in the demo), ``k``, ``lam``, ``mu``.
    """
    import inspect
    demo = demo_module("ironing")
    kw = _step_kw(case)
    if demo is not None and (DEMOS / "ironing.toml").exists():
        from dolfinx_friction.scene.toml import load_scene
        base = load_scene(DEMOS / "ironing.toml")
        params = dict(nx=int(case.get("nx", 40)), ny=int(case.get("ny", 8)))
        accepted = inspect.signature(demo.build_mesh).parameters
        if "n_arc" in accepted:
            params["n_arc"] = int(case.get("n_arc", 16))
        mesh = cached_mesh("ironing_demo", demo.build_mesh, **params)
        h = demo.LENGTH / params["nx"]
        c = base.contacts[0]
        slave_body = next((b for b in base.bodies if c.slave.startswith(b.name)), base.bodies[0])
        pair = _contact(case, c.slave, c.master, h, slave_body.E, c.mu)
        press, drag = base.steps[0], base.steps[-1]
        travel = float(case.get("travel", 4.0))
        if press.rigid:  # a [[rigid]] die
            start, end = press.rigid[0].displacement, drag.rigid[0].displacement
            drag = replace(drag, rigid=(replace(drag.rigid[0], displacement=(
                start[0] + travel, *end[1:])),))
            info = dict(rigid=press.rigid[0].name)
            h_master = h
        else:  # an elastic die driven through its top face
            moved = drag.bcs[-1]
            start = next(b.u for b in press.bcs if b.on == moved.on)
            bcs = tuple(b if b.on != moved.on else replace(b, u=(start[0] + travel, *b.u[1:]))
                        for b in drag.bcs)
            drag = replace(drag, bcs=bcs)
            info = dict(reaction=moved.on)
            radius = getattr(demo, "RADIUS", 2.0)
            h_master = math.pi * radius / params["n_arc"] if "n_arc" in params else h
        if "slide_faces" in case:
            increments = max(1, round(travel / (case["slide_faces"] * h_master)))
        else:
            increments = int(case.get("increments", drag.increments))
        steps = (replace(press, increments=int(case.get("press_increments", press.increments)),
                         **kw),
                 replace(drag, increments=increments, **kw))
        info.update(h=h, h_master=h_master, increments=increments, source="demos/ironing.py")
        return replace(base, mesh=mesh, contacts=(pair,), steps=steps), info
    from dolfinx_friction.scene.model import BC, Body, Scene, Step
    h = float(case.get("h", 0.1))
    ratio = float(case.get("ratio", 1.0))
    mesh = cached_mesh("ironing", build_ironing, h_slave=h, ratio=ratio)
    if "increments" in case:
        increments = int(case["increments"])
    else:
        increments = max(1, round(IRON_SLIDE / (case.get("slide_faces", 0.25) * h / ratio)))
    steps = (Step("press", increments=int(case.get("press_increments", 2)),
                  bcs=(BC("strip_bottom", (0.0, 0.0)), BC("punch_top", (0.0, -IRON_PRESS))), **kw),
             Step("slide", increments=increments,
                  bcs=(BC("punch_top", (IRON_SLIDE, -IRON_PRESS)),), **kw))
    scene = Scene(mesh=mesh, bodies=(Body("punch", IRON_E_PUNCH, NU), Body("strip", E, NU)),
                  contacts=(_contact(case, "punch_surface", "strip_top", h, IRON_E_PUNCH, 0.3),),
                  steps=steps)
    return scene, dict(h=h, reaction="punch_top", increments=increments,
                       source="benchmarks/stability/_scenes.py")


def block3d_scene(case: dict):
    """The 3D sliding block demo, coarse (3 x 3 slave faces on 6 x 3 master faces)."""
    from dolfinx_friction.scene.toml import load_scene
    demo = demo_module("sliding_block")
    mesh = cached_mesh("block3d", demo.build_mesh, n_block=int(case.get("n_block", 3)),
                       n_found=(6, 3), layers=(1, 1))
    base = load_scene(DEMOS / "sliding_block.toml")
    h = 20.0 / int(case.get("n_block", 3))
    c = base.contacts[0]
    pair = _contact(case, c.slave, c.master, h, base.body("block").E, c.mu)
    steps = list(base.steps)
    steps[-1] = replace(steps[-1], increments=int(case.get("increments", steps[-1].increments)))
    steps = tuple(replace(s, **_step_kw(case)) for s in steps)
    return (replace(base, mesh=mesh, contacts=(pair,), steps=steps),
            dict(h=h, reaction="block_top", increments=steps[-1].increments))


def groove_scene(case: dict):
    """The convex tip pressed 0.005 into the concave V-groove (:func:`build_groove`);
    ``increments`` (1), ``k``, ``mu`` (0), ``pairing``, ... (tests/verification/
    test_stability.py pins the chattering it shows)."""
    from dolfinx_friction.scene.model import BC, Body, Scene, Step
    h = 0.0625
    mesh = cached_mesh("groove", build_groove, h=h)
    kw = _step_kw(case)
    steps = (Step("press", increments=int(case.get("increments", 1)),
                  bcs=(BC("foundation_bottom", (0.0, 0.0)), BC("block_top", (0.0, -0.005))),
                  **kw),)
    scene = Scene(mesh=mesh, bodies=(Body("block", E, NU), Body("foundation", E, NU)),
                  contacts=(_contact(case, "tip", "groove", h, E, 0.0),), steps=steps)
    return scene, dict(h=h, reaction="block_top", increments=steps[0].increments)


SCENES = {"block": block_scene, "hertz": hertz_scene, "ironing": ironing_scene,
          "block3d": block3d_scene, "groove": groove_scene}


# ------------------------------------------------------------------------------ runs
def _normal_axis(gdim: int) -> int:
    return gdim - 1


def _measures(family: str, case: dict, info: dict, incs: list, problem) -> dict:
    """Force histories, the 'contact lost' flag and the accuracy numbers of a run.

    * ``Fn``, ``Ft``: normal and tangential reaction on the loaded face, last increment.
    * ``lost``: an increment was accepted while the contact that carries the load had
      vanished: no slave node in contact, or the normal force below 10 % of its value at
      the end of the press (the prescribed indentation never decreases, so the force
      cannot physically drop that far).  Such an increment is *wrong*, not converged.
    * ``ratio`` = Ft / Fn at the end (block: = mu in full slip; ironing: mean over the
      second half of the slide, ``ratio_osc`` its range, ``Fn_osc`` the range of Fn over
      its mean: the force noise of a faceted master).
    * ``p_max`` (hertz): the largest nodal pressure, compared with Hertz's p0.
    """
    out: dict = {}
    if "rigid" in info:  # the force of the obstacle's constraint, on the obstacle
        R = [inc.rigid_f[info["rigid"]] for inc in incs]
    else:
        R = [inc.reactions[info["reaction"]] for inc in incs]
    if not R:
        return out
    ax = _normal_axis(len(R[0]))
    fn = [float(abs(r[ax])) for r in R]
    ft = [float(abs(r[0])) for r in R]
    out.update(Fn=fn[-1], Ft=ft[-1], fn_hist=fn, active_hist=[i.active for i in incs],
               step_hist=[i.step for i in incs])
    press = [f for f, inc in zip(fn, incs) if inc.step == 0]
    ref = press[-1] if press and incs[0].step == 0 and len(press) == sum(
        1 for i in incs if i.step == 0) else max(fn)
    later = [(f, inc.active) for f, inc in zip(fn, incs) if inc.step > 0 or inc is incs[-1]]
    out["lost"] = bool(any(a == 0 or f < 0.1 * ref for f, a in later))
    if fn[-1] > 0:
        out["ratio"] = ft[-1] / fn[-1]
    if family == "ironing":
        slide = [(a, b) for a, b, inc in zip(ft, fn, incs) if inc.step > 0]
        half = slide[len(slide) // 2:]
        if len(half) >= 2 and min(b for _, b in half) > 0:
            r = [a / b for a, b in half]
            fns = [b for _, b in half]
            out["ratio"] = sum(r) / len(r)
            out["ratio_osc"] = max(r) - min(r)
            out["Fn_osc"] = (max(fns) - min(fns)) / (sum(fns) / len(fns))
    if family == "hertz":
        from mpi4py import MPI
        from dolfinx_friction.reference.analytic import effective_modulus, hertz_line
        _, p0 = hertz_line(2.0 * fn[-1], 10.0, effective_modulus(E, NU, E, NU))
        state = problem.pair_of(problem.scene.contacts[0]).state()
        p = state.pressure[state.has_element]
        out["p0_hertz"] = float(p0)
        out["p_max"] = float(MPI.COMM_WORLD.allreduce(p.max(initial=0.0), op=MPI.MAX))
    return out


def run_case(case: dict) -> dict:
    """Run one case; returns the case with its outcome.  Never raises.

    ``status``: ``ok`` (converged, no cutback), ``cutback`` (converged after cutbacks),
    ``failed`` (ConvergenceError after all cutbacks), ``error`` (anything else: a bug).
    A converged run with ``lost`` set accepted an increment without its contact (see
    :func:`_measures`).  The solver is driven as :func:`dolfinx_friction.scene.runner.run` drives it
    (same observer, same penetration criterion), so that a failed run still reports its
    iterations.
    """
    from dolfinx_friction.scene.runner import PENETRATION_WARNING
    from dolfinx_friction.scene.build import ContactProblem
    from dolfinx_friction.scene.driver import ConvergenceError, Solver
    out = dict(case)
    t0 = time.perf_counter()
    incs: list = []
    try:
        scene, info = SCENES[case["family"]](case)
        out["h"] = info["h"]
        out["n_increments"] = info["increments"]
        problem = ContactProblem(scene)
        solver = Solver(problem)
        try:
            solver.run(incs.append)
            out["status"] = "ok" if solver.summary.cutbacks == 0 else "cutback"
        except ConvergenceError as exc:
            out.update(status="failed", message=str(exc))
        s = solver.summary
        out.update(cutbacks=s.cutbacks, newton=s.newton_iterations, increments=len(incs),
                   t_reached=incs[-1].t if incs else 0.0,
                   iterations=[i.iterations for i in incs])
        if incs:
            pen = max(max(i.penetration.values(), default=0.0) for i in incs)
            out.update(max_iterations=max(i.iterations for i in incs),
                       mean_iterations=sum(i.iterations for i in incs) / len(incs),
                       penetration=pen, warned=bool(pen > PENETRATION_WARNING),
                       active=incs[-1].active, slipping=incs[-1].slipping)
            # slave nodes in contact reported as having slid off the master surface
            off = [(i.t, sum(getattr(i, "detached", {}).values())) for i in incs]
            out.update(detached=sum(n for _, n in off),
                       detached_t=[t for t, n in off if n])
            out.update(_measures(case["family"], case, info, incs, problem))
    except Exception as exc:  # noqa: BLE001  -- reported as an 'error' cell, never hidden
        import traceback
        out.update(status="error", message=f"{type(exc).__name__}: {exc}",
                   traceback=traceback.format_exc()[-2000:])
    out["wall"] = time.perf_counter() - t0
    return out


if __name__ == "__main__":  # a single case from the command line, for reproducers
    print(json.dumps(run_case(json.loads(sys.argv[1])), default=float, indent=1))
