"""Scene files: parsing, defaults, ``--set`` overrides and rejected inputs.

Pure Python (no dolfinx, no MPI): under ``mpirun -n 2`` every rank runs the
same checks in its own ``tmp_path``.
"""
from __future__ import annotations

import copy
import json
import math
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dolfinx_friction.cli.exits import EXIT_INPUT, classify
from dolfinx_friction.scene.model import (
    BC,
    Body,
    ContactPair,
    Load,
    Output,
    Rigid,
    SolverSettings,
    RigidMotion,
    Scene,
    Step,
)
from dolfinx_friction.scene.toml import (
    SceneError,
    apply_override,
    default_output_dir,
    load_scene,
    parse_scene,
    parse_value,
)

# The example of scene-format.md, verbatim.
EXAMPLE = '''\
title = "elastic block pressed and slid on an elastic foundation"

[mesh]
file = "block_slide_3d.msh"     # path relative to this scene file; Gmsh .msh 2.2 or 4.1

[[body]]
name = "block"                  # physical group of cells (3D: volume, 2D: surface)
E = 200000.0
nu = 0.3

[[body]]
name = "foundation"
E = 200000.0
nu = 0.3

[[contact]]
slave = "block_bottom"          # physical group of facets: its nodes are the slave nodes
master = "foundation_top"       # physical group of facets, or the name of a [[rigid]] obstacle
law = "linear"                  # linear | exponential | tabular | hard
K = 1.0e6                       # linear law: pressure per unit overclosure [F/L^3]
sigma_inf = 2.857               # linear law: tension plateau [F/L^2]
c0 = 1.0e-3                     # linear law: dimensionless cutoff factor (cutoff = c0*sqrt(A_p))
mu = 0.3                        # Coulomb coefficient; absent or 0 = frictionless
stick_slope = 1.0e4             # lambda [F/L^3]; tangential spring K_t = lambda * A_p

[[step]]
name = "press"
increments = 1                  # initial number of equal increments

  [[step.bc]]
  on = "foundation_bottom"
  u = [0.0, 0.0, 0.0]

  [[step.bc]]
  on = "block_top"
  u = [0.0, 0.0, -0.001]

[[step]]
name = "slide"
increments = 10

  [[step.bc]]
  on = "block_top"
  u = [0.02, 0.0, -0.001]

[output]
reactions = ["block_top", "foundation_bottom"]
'''

# A 3D ball (rigid) pressed into a block, then force-controlled.
RIGID_3D = '''\
[mesh]
file = "meshes/ball.msh"

[[body]]
name = "block"
E = 1000.0
nu = 0.25

[[rigid]]
name = "ball"
shape = "sphere"
center = [0.0, 0.0, 1.5]
radius = 0.5

[[contact]]
slave = "block_top"
master = "ball"
law = "hard"
mu = 0.2

[[step]]
  [[step.bc]]
  on = "block_bottom"
  u = [0, 0, 0]
  [[step.rigid]]
  name = "ball"
  displacement = [0, 0, -0.01]

[[step]]
name = "hold"
increments = 4
max_cutbacks = 0
newton_rtol = 1e-8
newton_atol = 1e-12
max_iterations = 50
line_search = true
  [[step.rigid]]
  name = "ball"
  force = [0.0, 0.0, -5.0]
  [[step.load]]
  on = "block_side"
  pressure = 1.5
'''

# A 2D disk (plane stress) on a rigid floor, exponential law.
RIGID_2D = '''\
[mesh]
file = "disk.MSH"

[[body]]
name = "disk"
E = 70.0e3
nu = 0.33
plane = "stress"
thickness = 0.1
degree = 2

[[rigid]]
name = "floor"
shape = "plane"
point = [0.0, -1.0]
normal = [0, 1]

[[contact]]
slave = "disk_edge"
master = "floor"
law = "exponential"
c0 = 1e-3
p0 = 10.0
tangent = "calculix"
pairing_iterations = 1

[[step]]
name = "drop"
  [[step.bc]]
  on = "disk_top"
  u = ["free", -0.01]
  [[step.load]]
  on = "disk_side"
  traction = [1.0, 0]

[output]
dir = "../out"
fields = false
contact_table = false
reactions = []
'''

BASES = {"example": EXAMPLE, "rigid3d": RIGID_3D, "rigid2d": RIGID_2D}


# --------------------------------------------------------------------------- helpers


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + "}"
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return repr(value)


def _is_array_of_tables(value: Any) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, dict) for v in value)


def to_toml(table: dict, prefix: str = "") -> str:
    """A minimal TOML writer for scene dictionaries (no stdlib writer exists)."""
    lines = [f"{k} = {_toml_value(v)}" for k, v in table.items()
             if not isinstance(v, dict) and not _is_array_of_tables(v)]
    for key, value in table.items():
        name = f"{prefix}.{key}" if prefix else key
        if isinstance(value, dict):
            lines += [f"[{name}]", to_toml(value, name)]
        elif _is_array_of_tables(value):
            for item in value:
                lines += [f"[[{name}]]", to_toml(item, name)]
    return "\n".join(lines)


def write(tmp_path: Path, text: str, name: str = "scene.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def base(name: str) -> dict:
    return tomllib.loads(BASES[name])


def _walk(data: Any, path: str) -> tuple[Any, Any]:
    *parents, last = [int(p) if p.isdigit() else p for p in path.split(".")]
    for part in parents:
        data = data[part]
    return data, last


Edit = Callable[[dict], None]


def put(path: str, value: Any) -> Edit:
    def edit(data: dict) -> None:
        node, last = _walk(data, path)
        node[last] = value
    return edit


def drop(path: str) -> Edit:
    def edit(data: dict) -> None:
        node, last = _walk(data, path)
        del node[last]
    return edit


def append(path: str, item: Any) -> Edit:
    def edit(data: dict) -> None:
        node, last = _walk(data, path)
        node.setdefault(last, []).append(item)
    return edit


def rename(path: str, new: str) -> Edit:
    def edit(data: dict) -> None:
        node, last = _walk(data, path)
        node[new] = node.pop(last)
    return edit


def edited(name: str, *edits: Edit) -> dict:
    data = copy.deepcopy(base(name))
    for edit in edits:
        edit(data)
    return data


def assert_one_line(error: SceneError) -> None:
    assert "\n" not in str(error)


# --------------------------------------------------------------------------- valid scenes


def test_example_parses_with_defaults(tmp_path):
    path = write(tmp_path, EXAMPLE)
    scene = load_scene(path)

    assert scene.title == "elastic block pressed and slid on an elastic foundation"
    assert scene.mesh == (tmp_path / "block_slide_3d.msh").resolve()
    assert scene.mesh.is_absolute()
    assert scene.source == path.resolve()
    assert scene.bodies == (
        Body(name="block", E=200000.0, nu=0.3, degree=None, plane="strain", thickness=1.0),
        Body(name="foundation", E=200000.0, nu=0.3),
    )
    assert scene.rigids == ()
    assert scene.contacts == (
        ContactPair(slave="block_bottom", master="foundation_top", law="linear", K=1.0e6,
                    sigma_inf=2.857, c0=1.0e-3, p0=None, table=None, mu=0.3, stick_slope=1.0e4,
                    tangent="consistent", pairing_iterations=8),
    )
    press, slide = scene.steps
    assert press == Step(
        name="press", increments=1, max_cutbacks=6, newton_rtol=1e-9, newton_atol=1e-10,
        max_iterations=30, line_search=True,
        bcs=(BC("foundation_bottom", (0.0, 0.0, 0.0)), BC("block_top", (0.0, 0.0, -0.001))),
    )
    assert slide == Step(name="slide", increments=10, bcs=(BC("block_top", (0.02, 0.0, -0.001)),))
    assert scene.output == Output(dir=None, reactions=("block_top", "foundation_bottom"),
                                  fields=True, contact_table=True)
    assert default_output_dir(scene) == path.resolve().parent / "scene_results"


def test_numbers_are_floats(tmp_path):
    scene = load_scene(write(tmp_path, RIGID_3D))
    bc = scene.steps[0].bcs[0]
    assert bc.u == (0.0, 0.0, 0.0) and all(type(c) is float for c in bc.u)
    assert all(type(c) is float for c in scene.steps[0].rigid[0].displacement)


def test_rigid_3d_scene(tmp_path):
    scene = load_scene(write(tmp_path, RIGID_3D))
    assert scene.mesh == (tmp_path / "meshes" / "ball.msh").resolve()
    assert scene.rigids == (Rigid(name="ball", shape="sphere", center=(0.0, 0.0, 1.5), radius=0.5),)
    assert scene.rigid("ball") is scene.rigids[0]
    pair = scene.contacts[0]
    assert (pair.law, pair.mu, pair.K, pair.sigma_inf, pair.c0, pair.stick_slope) == (
        "hard", 0.2, None, None, None, None)
    first, hold = scene.steps
    assert first.name == "step-0"  # default name: step-<index>, first step index 0
    assert first.rigid == (RigidMotion(name="ball", displacement=(0.0, 0.0, -0.01)),)
    assert hold == Step(name="hold", increments=4, max_cutbacks=0, newton_rtol=1e-8,
                        newton_atol=1e-12, max_iterations=50, line_search=True,
                        loads=(Load(on="block_side", pressure=1.5),),
                        rigid=(RigidMotion(name="ball", force=(0.0, 0.0, -5.0)),))
    assert scene.output == Output()


def test_default_step_name_uses_the_step_index(tmp_path):
    data = edited("example", drop("step.1.name"))
    scene = load_scene(write(tmp_path, to_toml(data)))
    assert [s.name for s in scene.steps] == ["press", "step-1"]


def test_rigid_2d_scene(tmp_path):
    sub = tmp_path / "scenes"
    sub.mkdir()
    path = write(sub, RIGID_2D)
    scene = load_scene(path)
    assert scene.mesh == (sub / "disk.MSH").resolve()
    assert scene.bodies == (Body("disk", 70.0e3, 0.33, degree=2, plane="stress", thickness=0.1),)
    assert scene.rigids == (Rigid("floor", "plane", point=(0.0, -1.0), normal=(0.0, 1.0)),)
    assert scene.contacts == (ContactPair("disk_edge", "floor", law="exponential", c0=1e-3, p0=10.0,
                                          tangent="calculix", pairing_iterations=1),)
    step = scene.steps[0]
    assert step.bcs == (BC("disk_top", (None, -0.01)),)
    assert step.loads == (Load("disk_side", traction=(1.0, 0.0)),)
    assert scene.output == Output(dir=(tmp_path / "out").resolve(), reactions=(), fields=False,
                                  contact_table=False)
    assert default_output_dir(scene) == (tmp_path / "out").resolve()


def test_rotating_rigid(tmp_path):
    """``[[rigid]] reference`` and ``[[step.rigid]] rotation``: an angle in 2D, kept as a
    1-tuple; a rotation vector in 3D."""
    data = edited("rigid3d", put("rigid.0.reference", [0, 0, 1]),
                  put("step.0.rigid.0.rotation", [0, 0.5, 0]))
    scene = load_scene(write(tmp_path, to_toml(data)))
    assert scene.rigids[0].reference == (0.0, 0.0, 1.0)
    assert scene.steps[0].rigid[0] == RigidMotion("ball", displacement=(0.0, 0.0, -0.01),
                                                  rotation=(0.0, 0.5, 0.0))
    assert scene.steps[1].rigid[0].rotation is None
    # ramped from 0 in its step, kept after it
    assert scene.rotation_at("ball", 0, 0.5) == (0.0, 0.25, 0.0)
    assert scene.rotation_at("ball", 1, 0.5) == (0.0, 0.5, 0.0)
    assert parse_scene(edited("rigid3d")).rotation_at("ball", 1, 0.5) is None
    data = edited("rigid2d", append("step.0.rigid", {"name": "floor", "displacement": [0, 0],
                                                     "rotation": 1}))
    scene = parse_scene(data)
    assert scene.steps[0].rigid[0].rotation == (1.0,)
    assert scene.rigids[0].reference is None


def test_cylinder_and_tabular(tmp_path):
    data = edited(
        "rigid3d",
        put("rigid.0", {"name": "ball", "shape": "cylinder", "point": [0, 0, 2], "axis": [0, 1, 0],
                        "radius": 1.0}),
        put("contact.0", {"slave": "block_top", "master": "ball", "law": "tabular", "c0": 2e-3,
                          "table": [[0, -1e-3], [1e3, 0.0], [5e3, 0.0], [6e3, 2e-3]]}),
    )
    scene = load_scene(write(tmp_path, to_toml(data)))
    assert scene.rigids[0] == Rigid("ball", "cylinder", point=(0.0, 0.0, 2.0), axis=(0.0, 1.0, 0.0),
                                    radius=1.0)
    # equal consecutive overclosures are accepted (the law separates them by 1e-10)
    assert scene.contacts[0].table == ((0.0, -1e-3), (1e3, 0.0), (5e3, 0.0), (6e3, 2e-3))
    assert scene.contacts[0].c0 == 2e-3  # the cutoff factor applies to every law


def test_solver_table(tmp_path):
    """``[solver]``: absent, the defaults ("auto"); given, its keys and PETSc options (kept
    sorted, as pairs); ``--set`` reaches it like any table."""
    assert load_scene(write(tmp_path, EXAMPLE)).solver == SolverSettings()
    data = edited("example", put("solver", {
        "linear": "iterative", "direct_max_dofs": 5000, "reuse_factorisation": False,
        "petsc_options": {"pc_type": "hypre", "ksp_rtol": 1e-8,
                          "ksp_norm_type": "unpreconditioned"}}))
    solver = load_scene(write(tmp_path, to_toml(data))).solver
    assert solver == SolverSettings("iterative", 5000, False, (
        ("ksp_norm_type", "unpreconditioned"), ("ksp_rtol", 1e-8), ("pc_type", "hypre")))
    path = write(tmp_path, EXAMPLE)
    assert load_scene(path, ["solver.linear=direct"]).solver.linear == "direct"
    assert load_scene(path, ["solver.chord=0"]).solver.chord == 0.0


def test_parse_scene_without_source_keeps_paths():
    scene = parse_scene(edited("rigid2d"))
    assert scene.mesh == Path("disk.MSH")
    assert scene.output.dir == Path("../out")
    assert scene.source is None


def test_default_output_dir_next_to_scene(tmp_path):
    scene = load_scene(write(tmp_path, RIGID_3D, name="ball_push.toml"))
    assert default_output_dir(scene) == tmp_path.resolve() / "ball_push_results"


# --------------------------------------------------------------------------- --set


def test_overrides_of_the_contract(tmp_path):
    path = write(tmp_path, EXAMPLE)
    scene = load_scene(path, [
        "contact.0.mu=0.2",
        "step.1.increments=20",
        "body.0.E=1e5",
        "step.0.bc.1.u=[0,0,-2e-3]",
        'step.0.bc.0.u.2="free"',
    ])
    assert scene.contacts[0].mu == 0.2
    assert scene.steps[1].increments == 20
    assert scene.bodies[0].E == 1e5 and scene.bodies[1].E == 200000.0
    assert scene.steps[0].bcs[1].u == (0.0, 0.0, -2e-3)
    assert scene.steps[0].bcs[0].u == (0.0, 0.0, None)


def test_distribution_of_the_slave_forces(tmp_path):
    """distribution: unset by default (resolved with the mesh: "mortar" for quadratic slave
    faces on a deformable master, else "nodal", as scene files of versions 1 and 2 had it),
    "mortar" or "nodal" from the file or --set."""
    path = write(tmp_path, EXAMPLE)
    assert load_scene(path).contacts[0].distribution is None
    assert load_scene(path, ["contact.0.distribution=nodal"]).contacts[0].distribution \
        == "nodal"
    assert load_scene(path, ["contact.0.distribution=mortar"]).contacts[0].distribution \
        == "mortar"
    path = write(tmp_path, to_toml(edited("example", put("contact.0.distribution", "mortar"))))
    assert load_scene(path).contacts[0].distribution == "mortar"


def test_calculix_penalty_and_stick_slope(tmp_path):
    """K and stick_slope: a number, or "calculix" (CalculiX's 50 E and E/2; also as a bare
    --set value); absent, the version-2 defaults 10 E/h and E/h once h is known."""
    path = write(tmp_path, EXAMPLE)
    scene = load_scene(path, ['contact.0.K="calculix"', "contact.0.stick_slope=calculix"])
    pair = scene.contacts[0]
    assert (pair.K, pair.stick_slope) == ("calculix", "calculix")
    E = scene.bodies[0].E
    resolved = pair.resolved(E, spacing=0.25)
    assert (resolved.K, resolved.stick_slope) == (50 * E, E / 2)
    default = replace(pair, K=None, stick_slope=None)
    assert (default.resolved(E).K, default.resolved(E).stick_slope) == (None, None)
    resolved = default.resolved(E, spacing=0.25)
    assert (resolved.K, resolved.stick_slope) == (40 * E, 4 * E)
    assert replace(pair, K=7.0).resolved(E, spacing=0.25).K == 7.0


def test_overrides_bare_strings_absent_keys_and_new_tables(tmp_path):
    path = write(tmp_path, EXAMPLE)
    scene = load_scene(path, [
        "step.0.bc.0.u.2=free",       # bare string
        "contact.0.law = hard",       # spaces around '=', bare string
        "contact.0.tangent=calculix",
        "body.1.degree=2",            # absent key of an existing table
        "step.0.line_search=true",
        "output.fields=false",
        "output.dir=results/run1",
        "mesh.file=other.msh",
        "title=a=b",                  # only the first '=' separates
    ])
    assert scene.steps[0].bcs[0].u == (0.0, 0.0, None)
    assert scene.contacts[0].law == "hard" and scene.contacts[0].tangent == "calculix"
    assert scene.bodies[1].degree == 2
    assert scene.steps[0].line_search is True
    assert scene.output.fields is False
    assert scene.output.dir == (tmp_path / "results" / "run1").resolve()
    assert scene.mesh == (tmp_path / "other.msh").resolve()
    assert scene.title == "a=b"
    # a missing [output] table is created by a dotted key
    scene = load_scene(write(tmp_path, RIGID_3D, name="r.toml"), ["output.contact_table=false"])
    assert scene.output.contact_table is False


def test_overrides_do_not_touch_the_file(tmp_path):
    path = write(tmp_path, EXAMPLE)
    load_scene(path, ["contact.0.mu=0.2"])
    assert path.read_text(encoding="utf-8") == EXAMPLE
    assert load_scene(path).contacts[0].mu == 0.3


@pytest.mark.parametrize("text, value", [
    ("0.2", 0.2), ("20", 20), ("1e5", 1e5), ("-3", -3), ("[0,0,-1]", [0, 0, -1]),
    ('"free"', "free"), ("free", "free"), ("true", True), ("false", False),
    ('[0, "free", 1.5]', [0, "free", 1.5]), ("block top", "block top"), ("", ""),
    ("x.msh", "x.msh"), ("1\nother = 2", "1\nother = 2"), ("[1, 2", "[1, 2"),
])
def test_parse_value(text, value):
    assert parse_value(text) == value
    assert type(parse_value(text)) is type(value)


@settings(max_examples=50, deadline=None, database=None)  # no shared files under mpirun
@given(st.floats(min_value=0, max_value=1e6, allow_nan=False, allow_infinity=False))
def test_set_roundtrips_any_float(mu):
    data = edited("example")
    apply_override(data, f"contact.0.mu={mu!r}")
    assert parse_scene(data).contacts[0].mu == mu


# --------------------------------------------------------------------------- rejected scenes

TWO_D = (put("step.0.bc.0.u", ["free", 0.0]),)

BAD = [
    # (id, base, edits, fragments the message must contain)
    ("unknown-top-level-key", "example", [put("colour", "red")], ["colour: unknown key"]),
    ("unknown-key-in-body", "example", [put("body.1.density", 7.8e-9)], ["body.1.density"]),
    ("unknown-key-in-bc", "example", [put("step.0.bc.0.value", 1.0)], ["step.0.bc.0.value"]),
    ("misspelt-stick_slope", "example", [rename("contact.0.stick_slope", "stick_slop")],
     ["contact.0.stick_slop", "did you mean 'stick_slope'"]),
    ("title-not-a-string", "example", [put("title", 3)], ["title = 3"]),
    ("E-as-string", "example", [put("body.0.E", "2e5")], ['body.0.E = "2e5"', "number"]),
    ("bool-as-number", "example", [put("contact.0.mu", True)], ["contact.0.mu = true"]),
    ("bool-as-integer", "example", [put("step.0.increments", True)], ["step.0.increments"]),
    ("E-zero", "example", [put("body.0.E", 0.0)], ["body.0.E = 0.0", "> 0"]),
    ("E-negative", "example", [put("body.1.E", -1)], ["body.1.E = -1"]),
    ("E-infinite", "example", [put("body.0.E", math.inf)], ["body.0.E = inf", "finite"]),
    ("E-missing", "example", [drop("body.0.E")], ["body.0.E", "missing"]),
    ("nu-half", "example", [put("body.0.nu", 0.5)], ["body.0.nu = 0.5", "< 0.5"]),
    ("nu-minus-one", "example", [put("body.0.nu", -1.0)], ["body.0.nu = -1.0", "> -1"]),
    ("plane-unknown", "rigid2d", [put("body.0.plane", "strian")],
     ["body.0.plane", "did you mean 'strain'"]),
    ("thickness-zero", "rigid2d", [put("body.0.thickness", 0)], ["body.0.thickness"]),
    ("degree-3", "example", [put("body.0.degree", 3)], ["body.0.degree = 3"]),
    ("degree-float", "example", [put("body.0.degree", 1.0)], ["body.0.degree = 1.0"]),
    ("mu-negative", "example", [put("contact.0.mu", -0.1)], ["contact.0.mu = -0.1: must be >= 0"]),
    ("K-zero", "example", [put("contact.0.K", 0)], ["contact.0.K = 0"]),
    ("sigma_inf-negative", "example", [put("contact.0.sigma_inf", -2.0)], ["contact.0.sigma_inf"]),
    ("stick_slope-zero", "example", [put("contact.0.stick_slope", 0.0)], ["contact.0.stick_slope"]),
    ("K-unknown-string", "example", [put("contact.0.K", "calculx")],
     ['contact.0.K = "calculx"', 'a number > 0 or "calculix"', "did you mean 'calculix'"]),
    ("stick_slope-unknown-string", "example", [put("contact.0.stick_slope", "stiff")],
     ['contact.0.stick_slope = "stiff"', 'a number > 0 or "calculix"']),
    ("K-bool", "example", [put("contact.0.K", True)], ["contact.0.K = true", "number"]),
    ("c0-zero", "example", [put("contact.0.c0", 0.0)], ["contact.0.c0"]),
    ("unknown-law", "example", [put("contact.0.law", "exponental")],
     ['contact.0.law = "exponental"', "did you mean 'exponential'"]),
    ("unknown-tangent", "example", [put("contact.0.tangent", "exact")], ["contact.0.tangent"]),
    ("pairing_iterations-zero", "example", [put("contact.0.pairing_iterations", 0)],
     ["contact.0.pairing_iterations"]),
    ("exponential-without-p0", "rigid2d", [drop("contact.0.p0")], ["contact.0.p0", "exponential"]),
    ("exponential-negative-p0", "rigid2d", [put("contact.0.p0", -1.0)], ["contact.0.p0 = -1.0"]),
    ("tabular-without-table", "rigid3d", [put("contact.0.law", "tabular")],
     ["contact.0.table", "required"]),
    ("tabular-one-pair", "rigid3d", [put("contact.0.law", "tabular"),
                                     put("contact.0.table", [[0.0, 0.0]])], ["contact.0.table"]),
    ("tabular-decreasing", "rigid3d", [put("contact.0.law", "tabular"),
                                       put("contact.0.table", [[0, 0], [1, 2e-3], [2, 1e-3]])],
     ["contact.0.table.2.1"]),
    ("tabular-triple", "rigid3d", [put("contact.0.law", "tabular"),
                                   put("contact.0.table", [[0, 0, 1], [1, 1]])],
     ["contact.0.table.0"]),
    ("tabular-string-entry", "rigid3d", [put("contact.0.law", "tabular"),
                                         put("contact.0.table", [[0, 0], ["1", 1]])],
     ["contact.0.table.1.0"]),
    ("slave-equals-master", "example", [put("contact.0.master", "block_bottom")],
     ['contact.0.master = "block_bottom"']),
    ("slave-is-a-rigid", "rigid3d", [put("contact.0.slave", "ball"), put("contact.0.master", "x")],
     ['contact.0.slave = "ball"']),
    ("contact-missing-master", "example", [drop("contact.0.master")], ["contact.0.master"]),
    ("duplicate-contact-pair", "example", [append("contact", dict(base("example")["contact"][0]))],
     ["contact.1", "contact.0"]),
    ("unknown-shape", "rigid3d", [put("rigid.0.shape", "box")], ['rigid.0.shape = "box"']),
    ("sphere-without-radius", "rigid3d", [drop("rigid.0.radius")], ["rigid.0.radius", "sphere"]),
    ("sphere-radius-zero", "rigid3d", [put("rigid.0.radius", 0.0)], ["rigid.0.radius = 0.0"]),
    ("sphere-with-normal", "rigid3d", [put("rigid.0.normal", [0, 0, 1])], ["rigid.0.normal"]),
    ("plane-zero-normal", "rigid2d", [put("rigid.0.normal", [0.0, 0.0])],
     ["rigid.0.normal = [0.0, 0.0]", "zero"]),
    ("plane-with-radius", "rigid2d", [put("rigid.0.radius", 1.0)], ["rigid.0.radius"]),
    ("cylinder-zero-axis", "rigid3d", [put("rigid.0.shape", "cylinder"), rename("rigid.0.center",
                                       "point"), put("rigid.0.axis", [0, 0, 0])], ["rigid.0.axis"]),
    ("cylinder-in-2d", "rigid2d", [put("rigid.0.shape", "cylinder"), rename("rigid.0.normal",
                                   "axis"), put("rigid.0.radius", 1.0)], ["rigid.0.shape"]),
    ("duplicate-rigid-name", "rigid3d", [append("rigid", {"name": "ball", "shape": "plane",
                                         "point": [0, 0, 0], "normal": [0, 0, 1]})],
     ['rigid.1.name = "ball"']),
    ("rigid-vector-length", "rigid3d", [put("rigid.0.center", [0.0, 1.5])],
     ["rigid.0.center: has 2 components"]),
    ("u-too-long", "example", [put("step.0.bc.0.u", [0, 0, 0, 0])], ["step.0.bc.0.u"]),
    ("u-too-short", "example", [put("step.0.bc.0.u", [0])], ["step.0.bc.0.u = [0]"]),
    ("u-scalar", "example", [put("step.0.bc.0.u", 0.0)], ["step.0.bc.0.u = 0.0"]),
    ("u-mixed-lengths", "example", [put("step.1.bc.0.u", [0.02, 0.0])],
     ["step.1.bc.0.u: has 2 components"]),
    ("u-bad-string", "example", [put("step.0.bc.0.u", [0, "fixed", 0])],
     ['step.0.bc.0.u.1 = "fixed"', '"free"']),
    ("u-bool-entry", "example", [put("step.0.bc.0.u", [0, False, 0])], ["step.0.bc.0.u.1 = false"]),
    ("u-missing", "example", [drop("step.0.bc.0.u")], ["step.0.bc.0.u"]),
    ("bc-without-group", "example", [drop("step.0.bc.0.on")], ["step.0.bc.0.on"]),
    ("rigid-vs-bc-lengths", "rigid2d", [put("step.0.bc.0.u", [0, 0, 0])], ["step.0.bc.0.u"]),
    ("traction-vs-bc-lengths", "rigid2d", [put("step.0.load.0.traction", [1, 0, 0])],
     ["step.0.load.0.traction"]),
    ("increments-zero", "example", [put("step.0.increments", 0)], ["step.0.increments = 0"]),
    ("increments-fraction", "example", [put("step.1.increments", 1.5)],
     ["step.1.increments = 1.5"]),
    ("increments-word", "example", [put("step.1.increments", "ten")],
     ['step.1.increments = "ten"']),
    ("max_cutbacks-negative", "example", [put("step.0.max_cutbacks", -1)], ["step.0.max_cutbacks"]),
    ("max_iterations-zero", "example", [put("step.0.max_iterations", 0)],
     ["step.0.max_iterations"]),
    ("newton_rtol-zero", "example", [put("step.0.newton_rtol", 0.0)], ["step.0.newton_rtol"]),
    ("newton_atol-negative", "example", [put("step.0.newton_atol", -1e-10)],
     ["step.0.newton_atol"]),
    ("line_search-not-bool", "example", [put("step.0.line_search", 1)], ["step.0.line_search"]),
    ("duplicate-bc-group", "example", [put("step.0.bc.1.on", "foundation_bottom")],
     ['step.0.bc.1.on = "foundation_bottom"', "step.0.bc.0"]),
    ("duplicate-step-name", "example", [put("step.1.name", "press")], ['step.1.name = "press"']),
    ("explicit-name-clashes-default", "rigid3d", [put("step.1.name", "step-0")], ["step.1.name"]),
    ("empty-step-name", "example", [put("step.0.name", "")], ["step.0.name"]),
    ("load-traction-and-pressure", "rigid3d", [put("step.1.load.0.traction", [0, 0, 1])],
     ["step.1.load.0", "traction", "pressure"]),
    ("load-neither", "rigid3d", [drop("step.1.load.0.pressure")], ["step.1.load.0"]),
    ("load-pressure-bool", "rigid3d", [put("step.1.load.0.pressure", False)],
     ["step.1.load.0.pressure"]),
    ("step-rigid-unknown", "rigid3d", [put("step.0.rigid.0.name", "bal")],
     ['step.0.rigid.0.name = "bal"', "did you mean 'ball'"]),
    ("step-rigid-displacement-and-force", "rigid3d",
     [put("step.1.rigid.0.displacement", [0, 0, 0])],
     ["step.1.rigid.0"]),
    ("step-rigid-twice", "rigid3d", [append("step.0.rigid", {"name": "ball", "force": [0, 0, 1]})],
     ["step.0.rigid.1.name"]),
    ("step-rigid-without-rigids", "example", [append("step.0.rigid", {"name": "punch",
                                              "displacement": [0, 0, 0]})],
     ["step.0.rigid.0.name"]),
    ("mesh-missing", "example", [drop("mesh")], ["mesh", "missing"]),
    ("mesh-file-missing", "example", [drop("mesh.file")], ["mesh.file", "missing"]),
    ("mesh-file-not-msh", "example", [put("mesh.file", "block.vtk")], ['mesh.file = "block.vtk"']),
    ("mesh-not-a-table", "example", [put("mesh", "block.msh")], ["mesh"]),
    ("no-body", "example", [drop("body")], ["body", "missing"]),
    ("empty-body-list", "example", [put("body", [])], ["body"]),
    ("body-as-table", "example", [put("body", {"name": "b", "E": 1.0, "nu": 0.3})], ["body"]),
    ("duplicate-body-name", "example", [put("body.1.name", "block")], ['body.1.name = "block"']),
    ("no-step", "example", [drop("step")], ["step", "missing"]),
    ("empty-step-list", "example", [put("step", [])], ["step"]),
    ("reactions-not-a-list", "example", [put("output.reactions", "block_top")],
     ["output.reactions"]),
    ("reactions-number", "example", [put("output.reactions", ["block_top", 3])],
     ["output.reactions.1"]),
    ("fields-not-bool", "example", [put("output.fields", "yes")], ["output.fields"]),
    ("unknown-output-key", "example", [put("output.format", "vtk")], ["output.format"]),
    # numbers beyond the float range, not finite, or absurdly large
    ("E-overflows-default-K", "example", [put("body.0.E", 1e307)],
     ["body.0.E = 1e+307", "K = 50 E", "overflows"]),
    ("E-huge-integer", "example", [put("body.1.E", 10**400)], ["body.1.E = 1000", "finite"]),
    ("nu-nan", "example", [put("body.0.nu", math.nan)], ["body.0.nu = nan", "finite"]),
    ("u-nan", "example", [put("step.0.bc.0.u", [0.0, math.nan, 0.0])],
     ["step.0.bc.0.u.1 = nan", "finite"]),
    ("pressure-inf", "rigid3d", [put("step.1.load.0.pressure", -math.inf)],
     ["step.1.load.0.pressure = -inf", "finite"]),
    ("radius-inf", "rigid3d", [put("rigid.0.radius", math.inf)], ["rigid.0.radius = inf"]),
    ("center-nan", "rigid3d", [put("rigid.0.center", [0.0, math.nan, 0.0])],
     ["rigid.0.center.1 = nan"]),
    ("increments-huge-integer", "example", [put("step.1.increments", 10**400)],
     ["step.1.increments = 1000", "<= 1000000"]),
    ("increments-a-million-and-one", "example", [put("step.1.increments", 1_000_001)],
     ["step.1.increments = 1000001", "<= 1000000"]),
    ("max_cutbacks-51", "example", [put("step.0.max_cutbacks", 51)],
     ["step.0.max_cutbacks = 51", "<= 50"]),
    ("max_iterations-huge", "example", [put("step.0.max_iterations", 10**30)],
     ["step.0.max_iterations", "<= 10000"]),
    ("pairing_iterations-huge", "example", [put("contact.0.pairing_iterations", 2**63)],
     ["contact.0.pairing_iterations", "<= 10000"]),
    ("nested-too-deep", "example", [put("output.x", [[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]])],
     ["output.x.0.0...", "nested more than 32 levels"]),
    # tabular laws: pressures >= 0 and increasing
    ("tabular-negative-pressure", "rigid3d", [put("contact.0.law", "tabular"),
                                              put("contact.0.table", [[-1.0, 0], [1.0, 1e-3]])],
     ["contact.0.table.0.0 = -1.0", ">= 0"]),
    ("tabular-decreasing-pressure", "rigid3d",
     [put("contact.0.law", "tabular"), put("contact.0.table", [[0, 0], [2.0, 1e-3], [1.0, 2e-3]])],
     ["contact.0.table.2.0 = 1.0", "increase", "previous: 2"]),
    ("tabular-equal-pressures", "rigid3d",
     [put("contact.0.law", "tabular"), put("contact.0.table", [[0, 0], [1.0, 1e-3], [1.0, 2e-3]])],
     ["contact.0.table.2.0 = 1.0", "increase"]),
    ("tabular-nan-overclosure", "rigid3d",
     [put("contact.0.law", "tabular"), put("contact.0.table", [[0, 0], [1.0, math.nan]])],
     ["contact.0.table.1.1 = nan", "finite"]),
    # rotating obstacles
    ("rotation-angle-in-3d", "rigid3d", [put("step.0.rigid.0.rotation", 0.1)],
     ["step.0.rigid.0.rotation = [0.1]", "rotation vector of 3 numbers in 3D"]),
    ("rotation-vector-in-2d", "rigid2d", [append("step.0.rigid", {"name": "floor", "displacement":
                                          [0, 0], "rotation": [0, 0, 0.1]})],
     ["step.0.rigid.0.rotation", "an angle (a number) in 2D"]),
    ("rotation-two-numbers", "rigid3d", [put("step.0.rigid.0.rotation", [0.1, 0.2])],
     ["step.0.rigid.0.rotation = [0.1, 0.2]", "rotation vector of 3 numbers"]),
    ("rotation-nan", "rigid3d", [put("step.0.rigid.0.rotation", [0.0, math.nan, 0.0])],
     ["step.0.rigid.0.rotation.1 = nan", "finite"]),
    ("rotation-inf", "rigid2d", [append("step.0.rigid", {"name": "floor", "displacement": [0, 0],
                                                         "rotation": math.inf})],
     ["step.0.rigid.0.rotation = inf", "finite"]),
    ("rotation-string", "rigid3d", [put("step.0.rigid.0.rotation", "fast")],
     ['step.0.rigid.0.rotation = "fast"']),
    ("reference-length", "rigid3d", [put("rigid.0.reference", [0.0, 1.5])],
     ["rigid.0.reference: has 2 components"]),
    ("reference-nan", "rigid2d", [put("rigid.0.reference", [math.nan, 0.0])],
     ["rigid.0.reference.0 = nan", "finite"]),
    ("rotation-axisymmetric", "rigid2d", [put("body.0.plane", "axisymmetric"),
                                          drop("body.0.thickness"),
                                          append("step.0.rigid", {"name": "floor", "displacement":
                                                                  [0, 0], "rotation": 0.1})],
     ["step.0.rigid.0.rotation = [0.1]", "axisymmetric scene cannot turn"]),
    ("contact-method-unknown", "example", [put("contact.0.method", "lagrange")],
     ['contact.0.method = "lagrange"', '"penalty", "augmented"']),
    ("contact-distribution-unknown", "example", [put("contact.0.distribution", "segment")],
     ['contact.0.distribution = "segment"', '"nodal", "mortar"']),
    ("augmented-tolerance-one", "example", [put("contact.0.augmented_tolerance", 1.0)],
     ["contact.0.augmented_tolerance = 1.0", "< 1"]),
    # [solver]: the linear solver; input files never run code nor choose files to write
    ("solver-unknown-kind", "example", [put("solver", {"linear": "cholesky"})],
     ['solver.linear = "cholesky"', '"auto", "direct", "iterative"']),
    ("solver-unknown-key", "example", [put("solver", {"kind": "direct"})],
     ["solver.kind", "unknown key"]),
    ("solver-negative-limit", "example", [put("solver", {"direct_max_dofs": -1})],
     ["solver.direct_max_dofs = -1"]),
    ("solver-chord-not-below-one", "example", [put("solver", {"chord": 1})],
     ["solver.chord = 1", "must be < 1"]),
    ("solver-solve-statuses-not-boolean", "example", [put("solver", {"solve_statuses": 1})],
     ["solver.solve_statuses = 1"]),
    ("solver-options-not-a-table", "example", [put("solver", {"petsc_options": "-ksp_type cg"})],
     ["solver.petsc_options", "table of PETSc options"]),
    ("solver-option-with-dash", "example", [put("solver", {"petsc_options": {"-ksp_type": "cg"}})],
     ["solver.petsc_options.-ksp_type", "without its dash"]),
    ("solver-option-python", "example",
     [put("solver", {"petsc_options": {"pc_type": "python", "pc_python_type": "m.C"}})],
     ["solver.petsc_options.pc_", "would load Python code"]),
    ("solver-option-view-file", "example",
     [put("solver", {"petsc_options": {"ksp_view": "ascii:/etc/motd"}})],
     ["solver.petsc_options.ksp_view", "would write a file"]),
    ("solver-option-list", "example", [put("solver", {"petsc_options": {"ksp_rtol": [1e-8]}})],
     ["solver.petsc_options.ksp_rtol", "string, a number or true/false"]),
]


@pytest.mark.parametrize("base_name, edits, fragments",
                         [pytest.param(b, e, f, id=i) for i, b, e, f in BAD])
def test_bad_scene(tmp_path, base_name, edits, fragments):
    path = write(tmp_path, to_toml(edited(base_name, *edits)))
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: ")
    for fragment in fragments:
        assert fragment in message
    assert_one_line(caught.value)


def test_enough_distinct_bad_cases():
    assert len({case[0] for case in BAD}) == len(BAD) >= 35


def test_bases_are_valid(tmp_path):
    for name in BASES:
        parse_scene(edited(name), source=tmp_path / f"{name}.toml")
        parse_scene(tomllib.loads(to_toml(edited(name))))  # the test writer round-trips


BAD_SETS = [
    ("no-equals", "contact.0.mu", ["--set contact.0.mu", "KEY=VALUE"]),
    ("empty-key", "=3", ["--set =3"]),
    ("empty-segment", "contact..mu=0.2", ["contact..mu"]),
    ("index-out-of-range", "step.2.increments=20", ["step.2", "out of range"]),
    ("vector-index-out-of-range", "step.0.bc.0.u.3=0", ["step.0.bc.0.u.3"]),
    ("negative-index", "contact.-1.mu=0.2", ["contact.-1"]),
    ("name-as-index", "body.block.E=1e5", ["body.block"]),
    ("into-a-number", "body.0.E.value=1", ["body.0.E"]),
    ("missing-array", "rigid.0.radius=1", ["rigid"]),
    ("unknown-key-validated", "contact.0.muu=0.2", ["contact.0.muu", "did you mean 'mu'"]),
    ("bad-value-validated", "step.1.increments=0", ["step.1.increments = 0"]),
    ("bad-free-validated", "step.0.bc.0.u.2=fre", ['step.0.bc.0.u.2 = "fre"']),
    ("unknown-table-validated", "outptu.fields=false", ["outptu", "did you mean 'output'"]),
    ("inf", "body.0.E=inf", ["body.0.E = inf", "finite"]),
    ("nan-component", "step.0.bc.0.u.1=nan", ["step.0.bc.0.u.1 = nan", "finite"]),
    ("beyond-float-range", "contact.0.mu=1e400", ["contact.0.mu = inf", "finite"]),
    ("huge-integer", "step.1.increments=1" + "0" * 400, ["step.1.increments", "<= 1000000"]),
    ("nested-900-deep", "body.0.E=" + "[" * 900 + "]" * 900, ["body.0.E", "must be a number"]),
]


@pytest.mark.parametrize("assignment, fragments",
                         [pytest.param(a, f, id=i) for i, a, f in BAD_SETS])
def test_bad_override(tmp_path, assignment, fragments):
    path = write(tmp_path, EXAMPLE)
    with pytest.raises(SceneError) as caught:
        load_scene(path, [assignment])
    message = str(caught.value)
    assert message.startswith(f"{path}: ")
    for fragment in fragments:
        assert fragment in message
    assert_one_line(caught.value)


def test_toml_syntax_error_names_file_and_line(tmp_path):
    lines = EXAMPLE.splitlines()
    lines[8] = "E = = 200000.0"  # line 9
    path = write(tmp_path, "\n".join(lines))
    with pytest.raises(SceneError) as caught:
        load_scene(path)
    message = str(caught.value)
    assert message.startswith(f"{path}:9:")
    assert "TOML" in message
    assert_one_line(caught.value)


def test_duplicate_toml_key_is_a_syntax_error(tmp_path):
    path = write(tmp_path, EXAMPLE.replace("nu = 0.3\n", "nu = 0.3\nnu = 0.2\n", 1))
    with pytest.raises(SceneError, match=r"scene\.toml:\d+"):
        load_scene(path)


def test_byte_order_mark_is_skipped(tmp_path):
    plain = load_scene(write(tmp_path, EXAMPLE))
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + EXAMPLE.encode())
    assert load_scene(path).bodies == plain.bodies
    path.write_bytes(b"\xef\xbb\xbf" + EXAMPLE.replace("E = 200000.0", "E = = 1", 1).encode())
    with pytest.raises(SceneError, match=r"bom\.toml:8:5: TOML"):  # lines counted as without it
        load_scene(path)


@pytest.mark.parametrize("depth", [600, 1000])
@pytest.mark.parametrize("kind", ["array", "table"])
def test_deeply_nested_toml(tmp_path, depth, kind):
    value = ("[" * depth + "]" * depth if kind == "array"
             else "{a = " * depth + "1" + "}" * depth)
    path = write(tmp_path, f"x = {value}\n" + EXAMPLE)
    with pytest.raises(SceneError, match="nested too deeply") as caught:
        load_scene(path)
    assert str(caught.value).startswith(f"{path}: ")
    assert_one_line(caught.value)


def test_missing_scene_file(tmp_path):
    path = tmp_path / "nowhere.toml"
    with pytest.raises(SceneError, match="nowhere.toml"):
        load_scene(path)


def test_scene_error_is_a_value_error_with_key():
    with pytest.raises(ValueError, match=r"^contact\.0\.mu = -0\.1: must be >= 0$"):
        parse_scene(edited("example", put("contact.0.mu", -0.1)))
    with pytest.raises(SceneError) as caught:
        parse_scene(edited("example", put("contact.0.mu", -0.1)), source="scene.toml")
    assert str(caught.value) == "scene.toml: contact.0.mu = -0.1: must be >= 0"
    assert caught.value.key == "contact.0.mu"
    assert caught.value.source == "scene.toml"


# --------------------------------------------------------------------------- the Python API

# (id, a model object built in Python, base, the same value in a scene file, the indexed
#  table of the file that the Python message names without its index)
SAME_RULES = [
    ("mu-negative", lambda: ContactPair("a", "b", mu=-0.1), "example", put("contact.0.mu", -0.1),
     "contact.0", "contact"),
    ("mu-bool", lambda: ContactPair("a", "b", mu=True), "example", put("contact.0.mu", True),
     "contact.0", "contact"),
    ("law", lambda: ContactPair("a", "b", law="exponental"), "example",
     put("contact.0.law", "exponental"), "contact.0", "contact"),
    ("p0-missing", lambda: ContactPair("a", "b", law="exponential"), "rigid2d",
     drop("contact.0.p0"), "contact.0", "contact"),
    ("table-decreasing", lambda: ContactPair("a", "b", law="tabular",
                                             table=((0, 0), (1, 2e-3), (2, 1e-3))),
     "rigid3d", lambda d: (put("contact.0.law", "tabular")(d),
                           put("contact.0.table", [[0, 0], [1, 2e-3], [2, 1e-3]])(d)),
     "contact.0", "contact"),
    ("self-contact", lambda: ContactPair("block_bottom", "block_bottom"), "example",
     put("contact.0.master", "block_bottom"), "contact.0", "contact"),
    ("E-zero", lambda: Body("b", E=0.0, nu=0.3), "example", put("body.0.E", 0.0), "body.0", "body"),
    ("E-overflows", lambda: Body("b", E=1e307, nu=0.3), "example", put("body.0.E", 1e307),
     "body.0", "body"),
    ("nu-nan", lambda: Body("b", E=1.0, nu=math.nan), "example", put("body.0.nu", math.nan),
     "body.0", "body"),
    ("degree-float", lambda: Body("b", E=1.0, nu=0.3, degree=1.0), "example",
     put("body.0.degree", 1.0), "body.0", "body"),
    ("shape", lambda: Rigid("ball", "box"), "rigid3d", put("rigid.0.shape", "box"),
     "rigid.0", "rigid"),
    ("radius-missing", lambda: Rigid("ball", "sphere", center=(0.0, 0.0, 0.0)), "rigid3d",
     drop("rigid.0.radius"), "rigid.0", "rigid"),
    ("zero-normal", lambda: Rigid("floor", "plane", point=(0, 0), normal=[0.0, 0.0]), "rigid2d",
     put("rigid.0.normal", [0.0, 0.0]), "rigid.0", "rigid"),
    ("u-bad-string", lambda: BC("top", [0, "fixed", 0]), "example",
     put("step.0.bc.0.u", [0, "fixed", 0]), "step.0.bc.0", "step.bc"),
    ("u-too-short", lambda: BC("top", [0]), "example", put("step.0.bc.0.u", [0]),
     "step.0.bc.0", "step.bc"),
    ("load-both", lambda: Load("side", traction=(0.0, 0.0, 1.0), pressure=1.5), "rigid3d",
     put("step.1.load.0.traction", [0.0, 0.0, 1.0]), "step.1.load.0", "step.load"),
    ("motion-neither", lambda: RigidMotion("ball"), "rigid3d", drop("step.0.rigid.0.displacement"),
     "step.0.rigid.0", "step.rigid"),
    ("increments-zero", lambda: Step("s", increments=0), "example", put("step.0.increments", 0),
     "step.0", "step"),
    ("max_cutbacks-51", lambda: Step("s", max_cutbacks=51), "example",
     put("step.0.max_cutbacks", 51), "step.0", "step"),
    ("line_search-int", lambda: Step("s", line_search=1), "example",
     put("step.0.line_search", 1), "step.0", "step"),
    ("duplicate-bc", lambda: Step("s", bcs=(BC("foundation_bottom", (0, 0, 0)),
                                             BC("foundation_bottom", (0, 0, 0)))), "example",
     put("step.0.bc.1.on", "foundation_bottom"), "step.0", "step"),
    ("reactions-number", lambda: Output(reactions=("block_top", 3)), "example",
     put("output.reactions", ["block_top", 3]), "output", "output"),
]


@pytest.mark.parametrize("build, base_name, edit, indexed, table",
                         [pytest.param(*case[1:], id=case[0]) for case in SAME_RULES])
def test_python_objects_follow_the_file_rules(build, base_name, edit, indexed, table):
    """A model object built in Python is refused with the scene file's message, its key
    path without the table's index (``contact.mu`` for ``contact.0.mu``)."""
    with pytest.raises(SceneError) as in_file:
        parse_scene(edited(base_name, edit))
    with pytest.raises(SceneError) as in_python:
        build()
    assert indexed in in_file.value.detail
    assert in_python.value.detail == in_file.value.detail.replace(indexed, table)
    assert in_python.value.key == in_file.value.key.replace(indexed, table)
    assert_one_line(in_python.value)


def test_python_scene_checks_name_the_scene_entries():
    """The checks across a Scene index its tuples, as in a file."""
    data = edited("example", append("contact", dict(base("example")["contact"][0])))
    with pytest.raises(SceneError) as in_file:
        parse_scene(data)
    scene = parse_scene(edited("example"))
    with pytest.raises(SceneError) as in_python:
        Scene(mesh=scene.mesh, bodies=scene.bodies, steps=scene.steps,
              contacts=scene.contacts * 2)
    assert str(in_python.value) == str(in_file.value) == "contact.1: same slave and master as " \
                                                          "contact.0"
    with pytest.raises(SceneError, match="^body: needs at least 1 Body$"):
        Scene(mesh=scene.mesh, bodies=(), steps=scene.steps)
    with pytest.raises(SceneError, match="^output: must be of type Output$"):
        Scene(mesh=scene.mesh, bodies=scene.bodies, steps=scene.steps, output=None)
    with pytest.raises(SceneError, match="^step.bc: must be a sequence of BC$"):
        Step("s", bcs=({"on": "top", "u": [0, 0]},))


def test_python_values_are_converted_like_the_file():
    """A free component is None or "free"; sequences become tuples, numbers floats."""
    assert BC("top", [0.0, "free"]) == BC("top", [0.0, None]) == BC("top", (0.0, None))
    assert BC("top", [0, None]).u == (0.0, None) and isinstance(BC("top", [0, 1]).u[0], float)
    rigid = Rigid("floor", "plane", point=np.zeros(2), normal=np.array([0, 1]))
    assert rigid.point == (0.0, 0.0) and rigid.normal == (0.0, 1.0)
    assert Step("s", increments=np.int64(3), bcs=[BC("a", (0, 0))]).bcs == (BC("a", (0, 0)),)
    assert Output(dir="out", reactions=["a"]) == Output(dir=Path("out"), reactions=("a",))
    pair = ContactPair("a", "b", law="tabular", table=[[0, 0], [1, 1e-3]])
    assert pair.table == ((0.0, 0.0), (1.0, 1e-3))
    assert pair == parse_scene(edited("rigid3d", put("contact.0.law", "tabular"),
                                      put("contact.0.table", [[0, 0], [1, 1e-3]]),
                                      put("contact.0.slave", "a"), put("contact.0.master", "b"),
                                      drop("contact.0.mu"))).contacts[0]


def test_python_error_is_an_input_error():
    """The command line and scripts classify it as bad input (exit status 2), one line."""
    with pytest.raises(SceneError) as caught:
        ContactPair(slave="a", master="b", mu=-0.3)
    assert classify(caught.value) == (EXIT_INPUT, "contact.mu = -0.3: must be >= 0")
