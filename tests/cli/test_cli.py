"""The command line, through a subprocess: every bad input answered by one line.

``python -m dolfinx_friction run|check`` is run on a few tiny scenes and on many
broken variants of them.  A broken scene, mesh or argument must give

* a non-zero exit status (2: the input is at fault),
* exactly one non-empty line on stderr that names the key, group, value or
  file at fault, and no traceback.

Good scenes must exit 0 and write the files of shared/scene-format.md; a run
that diverges exits 3 and keeps only converged increments.

The subprocesses are started from a serial pytest only: under ``mpirun -n 2``
every test here is skipped (once is enough), and one test launches
``mpirun -n 2`` itself instead.  The broken-input cases are independent
subprocesses, so they are started a few at a time in a thread pool as soon as
the first one is needed; each test then waits for its own.
"""
from __future__ import annotations

import copy
import csv
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tomllib
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional

import numpy as np
import pytest
from mpi4py import MPI

from dolfinx_friction.reference import meshes

pytestmark = pytest.mark.skipif(
    MPI.COMM_WORLD.size > 1,
    reason="the CLI is tested through subprocesses from a serial pytest "
           "(test_mpirun_matches_serial launches mpirun -n 2 itself)")

ROOT = Path(__file__).resolve().parents[2]
TIMEOUT = 300
EXIT_INPUT, EXIT_DIVERGED = 2, 3
WORKERS = max(2, min(4, os.cpu_count() or 1))


# --------------------------------------------------------------------------- helpers

#: Where the subprocesses keep their bytecode (set by the ``workdir`` fixture): with
#: PYTHONDONTWRITEBYTECODE each of the ~90 subprocesses would compile every module again.
_PYCACHE: list[Path] = []


def cli_env() -> dict[str, str]:
    """The environment of a CLI subprocess: the package importable, no inherited MPI job."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("OMPI_COMM_WORLD", "OMPI_MCA_ess", "PMIX_", "PMI_"))}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in
                                        env.get("PYTHONPATH", "").split(os.pathsep) if p])
    env["PYTHONNOUSERSITE"] = "1"
    if _PYCACHE:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = str(_PYCACHE[0])
    return env


@dataclass
class Outcome:
    args: list[str]
    status: int
    stdout: str
    stderr: str

    def __str__(self) -> str:
        return (f"command: {' '.join(self.args)}\nexit status: {self.status}\n"
                f"--- stdout ---\n{self.stdout}--- stderr ---\n{self.stderr}")


def cli(*args: Any, cwd: Optional[Path] = None) -> Outcome:
    command = [sys.executable, "-m", "dolfinx_friction", *map(str, args)]
    proc = subprocess.run(command, capture_output=True, text=True, env=cli_env(), cwd=cwd,
                          timeout=TIMEOUT)
    return Outcome(command, proc.returncode, proc.stdout, proc.stderr)


def assert_one_line_error(out: Outcome, expect: list[str], status: int = EXIT_INPUT) -> str:
    """Exit ``status``, exactly one non-empty stderr line naming everything in ``expect``."""
    assert out.status == status, str(out)
    lines = out.stderr.splitlines()
    assert len(lines) == 1 and lines[0].strip(), f"expected one line on stderr\n{out}"
    assert "Traceback" not in out.stderr, str(out)
    line = lines[0]
    for text in expect:
        assert text in line, f"{text!r} not in the error line\n{out}"
    return line


def toml_dumps(data: dict) -> str:
    """A minimal TOML writer for scene dictionaries (tables, arrays of tables, values)."""
    def key(k: str) -> str:
        return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)

    def value(v: Any) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, float):
            assert math.isfinite(v)
            return repr(v)
        if isinstance(v, int):
            return str(v)
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{" + ", ".join(f"{key(k)} = {value(x)}" for k, x in v.items()) + "}"
        raise TypeError(type(v))

    def is_tables(v: Any) -> bool:
        return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)

    lines: list[str] = []

    def table(prefix: str, d: dict) -> None:
        for k, v in d.items():
            if not isinstance(v, dict) and not is_tables(v):
                lines.append(f"{key(k)} = {value(v)}")
        for k, v in d.items():
            if isinstance(v, dict):
                lines.append(f"\n[{prefix}{key(k)}]")
                table(f"{prefix}{key(k)}.", v)
            elif is_tables(v):
                for item in v:
                    lines.append(f"\n[[{prefix}{key(k)}]]")
                    table(f"{prefix}{key(k)}.", item)

    table("", data)
    return "\n".join(lines) + "\n"


DELETE = object()


def edited(data: dict, edits: list[tuple[str, Any]]) -> dict:
    """A copy of ``data`` with ``(dotted path, value)`` edits.

    ``DELETE`` removes the key; an array index one past the end appends.
    """
    data = copy.deepcopy(data)
    for path, new in edits:
        *parents, last = path.split(".")
        node: Any = data
        for p in parents:
            node = node[int(p)] if isinstance(node, list) else node.setdefault(p, {})
        if isinstance(node, list):
            if int(last) == len(node):  # one past the end: append
                node.append(new)
            else:
                node[int(last)] = new
        elif new is DELETE:
            del node[last]
        else:
            node[last] = new
    return data


# --------------------------------------------------------------------------- scenes

#: Block on a foundation, frictional contact, pressed then slid (mesh two.msh).
GOOD = {
    "title": "tiny block slid on a foundation",
    "mesh": {"file": "two.msh"},
    "body": [{"name": "block", "E": 1000.0, "nu": 0.3},
             {"name": "foundation", "E": 1000.0, "nu": 0.3}],
    "contact": [{"slave": "block_bottom", "master": "foundation_top", "mu": 0.3}],
    "step": [
        {"name": "press", "increments": 1,
         "bc": [{"on": "foundation_bottom", "u": [0.0, 0.0, 0.0]},
                {"on": "block_top", "u": [0.0, 0.0, -0.01]}]},
        {"name": "slide", "increments": 3,
         "bc": [{"on": "block_top", "u": [0.05, 0.0, -0.01]}]},
    ],
    "output": {"fields": False},
}

#: One block pressed onto a rigid plane (mesh block.msh: groups block, bottom, top,
#: side_x0, side_y0 and the edge group edge_x0y0).
RIGID = {
    "mesh": {"file": "block.msh"},
    "body": [{"name": "block", "E": 1000.0, "nu": 0.3}],
    "rigid": [{"name": "floor", "shape": "plane", "point": [0.0, 0.0, 0.0],
               "normal": [0.0, 0.0, 1.0]}],
    "contact": [{"slave": "bottom", "master": "floor", "mu": 0.2}],
    "step": [{"name": "press", "increments": 2,
              "bc": [{"on": "top", "u": [0.0, 0.0, -0.01]}],
              "rigid": [{"name": "floor", "displacement": [0.0, 0.0, 0.0]}]}],
    "output": {"fields": False},
}

#: A 2D strip on a rigid circle (mesh rect.msh: block, bottom, top, left, right).
PLANAR = {
    "mesh": {"file": "rect.msh"},
    "body": [{"name": "block", "E": 1000.0, "nu": 0.3}],
    "rigid": [{"name": "drum", "shape": "sphere", "center": [0.5, -0.5], "radius": 0.5}],
    "contact": [{"slave": "bottom", "master": "drum"}],
    "step": [{"bc": [{"on": "top", "u": [0.0, -0.001]}]}],
    "output": {"fields": False},
}

BASES = {"good": GOOD, "rigid": RIGID, "planar": PLANAR}


def _block_with_edge(path: Path) -> Path:
    """reference.meshes.block_3d (2x2x1 hexahedra) plus the edge group ``edge_x0y0``."""
    import gmsh

    def build():
        box = meshes.box(0, 0, 0, 1, 1, 0.5)
        meshes.mesh_boxes([(box, (2, 2, 1))])
        meshes.group(3, [box], "block")
        meshes.group(2, meshes.boundary(3, box, 2, 0.0), "bottom")
        meshes.group(2, meshes.boundary(3, box, 2, 0.5), "top")
        meshes.group(2, meshes.boundary(3, box, 0, 0.0), "side_x0")
        meshes.group(2, meshes.boundary(3, box, 1, 0.0), "side_y0")
        edges = [t for _, t in gmsh.model.getEntities(1)
                 if max(abs(c) for c in gmsh.model.occ.getCenterOfMass(1, t)[:2]) < 1e-9]
        meshes.group(1, edges, "edge_x0y0")
    return meshes.write_model(build, path)


def _with_empty_group(path: Path) -> Path:
    """A meshed box whose named group ``empty_group`` holds no element."""
    import gmsh

    def build():
        box = meshes.box(0, 0, 0, 1, 1, 1)
        meshes.mesh_boxes([(box, (1, 1, 1))])
        meshes.group(3, [box], "block")
        meshes.group(2, meshes.boundary(3, box, 2, 0.0), "bottom")
        meshes.group(2, [gmsh.model.addDiscreteEntity(2)], "empty_group")
    return meshes.write_model(build, path)


def _without_names(path: Path) -> Path:
    """A meshed box with physical groups that have no names."""
    import gmsh

    def build():
        box = meshes.box(0, 0, 0, 1, 1, 1)
        meshes.mesh_boxes([(box, (1, 1, 1))])
        gmsh.model.addPhysicalGroup(3, [box])
        gmsh.model.addPhysicalGroup(2, meshes.boundary(3, box, 2, 0.0))
    return meshes.write_model(build, path)


def _spanning_group(path: Path) -> Path:
    """reference.meshes.two_boxes (coarse) plus ``both_bottoms``: a facet group on both bodies."""
    def build():
        f = meshes.box(0, 0, 0, 1, 1, 0.5)
        b = meshes.box(0.25, 0.25, 0.5, 0.5, 0.5, 0.25)
        meshes.mesh_boxes([(f, (2, 2, 1)), (b, (1, 1, 1))])
        meshes.group(3, [f], "foundation")
        meshes.group(3, [b], "block")
        meshes.group(2, meshes.boundary(3, f, 2, 0.0), "foundation_bottom")
        meshes.group(2, meshes.boundary(3, f, 2, 0.5), "foundation_top")
        meshes.group(2, meshes.boundary(3, b, 2, 0.5), "block_bottom")
        meshes.group(2, meshes.boundary(3, b, 2, 0.75), "block_top")
        meshes.group(2, meshes.boundary(3, b, 2, 0.5) + meshes.boundary(3, f, 2, 0.0),
                      "both_bottoms")
    return meshes.write_model(build, path)


def _split_block(path: Path) -> Path:
    """One body ``block`` of two stacked unit hexahedra; ``middle`` is the face between them
    (interior to the body), ``bottom`` and ``top`` its outer faces."""
    import gmsh

    def build():
        a = meshes.box(0, 0, 0, 1, 1, 0.5)
        b = meshes.box(0, 0, 0.5, 1, 1, 0.5)
        gmsh.model.occ.fragment([(3, a)], [(3, b)])
        gmsh.model.occ.synchronize()
        meshes.mesh_boxes([(a, (1, 1, 1)), (b, (1, 1, 1))])
        meshes.group(3, [a, b], "block")
        meshes.group(2, meshes.boundary(3, a, 2, 0.0), "bottom")
        meshes.group(2, meshes.boundary(3, a, 2, 0.5), "middle")
        meshes.group(2, meshes.boundary(3, b, 2, 1.0), "top")
    return meshes.write_model(build, path)


def _moved_node(source: Path, path: Path, where: tuple, to: tuple) -> None:
    """``source`` with its node at ``where`` moved to ``to`` (NaN allowed)."""
    import gmsh
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.merge(str(source))
        tags, x, _ = gmsh.model.mesh.getNodes()
        k = int(np.argmin(np.linalg.norm(np.reshape(x, (-1, 3)) - where, axis=1)))
        gmsh.model.mesh.setNode(int(tags[k]), list(to), [])
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


@pytest.fixture(scope="module")
def workdir(tmp_path_factory) -> Path:
    """Meshes and base scenes, made once for the module."""
    d = tmp_path_factory.mktemp("cli")
    _PYCACHE[:] = [tmp_path_factory.getbasetemp() / "cli_pycache"]
    meshes.two_boxes(d / "two.msh", n_block=(2, 2, 1), n_foundation=(3, 3, 1))
    _block_with_edge(d / "block.msh")
    meshes.rectangle_2d(d / "rect.msh", n=(4, 1))
    _with_empty_group(d / "empty_group.msh")
    _without_names(d / "nonames.msh")
    (d / "corrupt.msh").write_bytes(b"\x00\x01 this is not a Gmsh file\n" * 4)
    text = (d / "two.msh").read_bytes()
    (d / "truncated.msh").write_bytes(text[: len(text) // 3])
    for name, data in BASES.items():
        written = toml_dumps(data)
        assert tomllib.loads(written) == data  # the writer is faithful
        (d / f"{name}.toml").write_text(written)
    (d / "a_file").write_text("not a directory\n")
    _hostile_inputs(d, text)
    _spanning_group(d / "spanning.msh")
    _split_block(d / "split.msh")
    rect = d / "rect.msh"
    _moved_node(rect, d / "rect_nan.msh", (0.5, 0.25, 0), (math.nan, 0.25, 0))
    _moved_node(rect, d / "rect_flat.msh", (0, 0.25, 0), (0, 0, 0))  # a cell of zero area
    _moved_node(rect, d / "rect_tangled.msh", (0.25, 0.25, 0), (0.25, -0.2, 0))
    (d / "bom.toml").write_bytes(b"\xef\xbb\xbf" + (d / "good.toml").read_bytes())
    return d


def _script(marker: Path) -> str:
    """A Gmsh .geo script that would create ``marker`` if gmsh ran it."""
    return f'SystemCall "touch {marker}";\nPoint(1) = {{0, 0, 0, 1}};\n'


def _hostile_inputs(d: Path, two_msh: bytes) -> None:
    """Files that are not what their names say: scripts, a FIFO, a device, huge counts."""
    (d / "script.msh").write_text(_script(d / "ran_script"))
    (d / "opt.msh").write_bytes(two_msh)  # a good mesh with an options script beside it
    (d / "opt.msh.opt").write_text(_script(d / "ran_opt"))
    os.mkfifo(d / "fifo.msh")
    os.mkfifo(d / "fifo.toml")
    (d / "zero.msh").symlink_to("/dev/zero")
    (d / "dir.msh").mkdir()
    (d / "v3.msh").write_bytes(two_msh.replace(b"4.1 0 8", b"3.0 0 8", 1))
    (d / "huge.msh").write_bytes(re.sub(rb"\$Nodes\n(\d+) \d+", rb"$Nodes\n\1 1000000000000",
                                        two_msh, count=1))


# --------------------------------------------------------------------------- bad inputs

@dataclass
class Case:
    """A broken input: ``base`` scene with ``edits`` (or ``text``), run with ``args``."""

    id: str
    expect: list[str]
    edits: list[tuple[str, Any]] = field(default_factory=list)
    base: str = "good"
    command: str = "check"
    args: list[str] = field(default_factory=list)
    text: Optional[str] = None           # the scene file's text instead of base + edits
    scene: Optional[str] = None          # the scene path argument instead of the case's file

    def scene_file(self, d: Path) -> Path:
        if self.scene is not None:
            return Path(self.scene.format(d=d))
        path = d / f"case_{self.id}.toml"
        path.write_text(self.text if self.text is not None
                        else toml_dumps(edited(BASES[self.base], self.edits)))
        return path

    def argv(self, d: Path) -> list[str]:
        return [self.command, str(self.scene_file(d))] + [a.format(d=d) for a in self.args]


CASES = [
    # unknown keys
    Case("unknown_top_key", ["colour", "unknown key"], [("colour", "red")]),
    Case("unknown_body_key", ["body.0.Young"], [("body.0.Young", 1000.0)]),
    Case("unknown_contact_key", ["contact.0.friction", "unknown key"],
         [("contact.0.friction", 0.3)]),
    Case("unknown_step_key", ["step.1.increment", "increments"], [("step.1.increment", 3)]),
    Case("unknown_bc_key", ["step.0.bc.1.value"], [("step.0.bc.1.value", [0.0, 0.0, 0.0])]),
    Case("unknown_output_key", ["output.reaction"], [("output.reaction", ["block_top"])]),
    # wrong types
    Case("E_is_a_string", ["body.0.E", '"stiff"'], [("body.0.E", "stiff")]),
    Case("increments_not_integer", ["step.1.increments", "2.5"], [("step.1.increments", 2.5)]),
    Case("mu_is_a_string", ["contact.0.mu", '"high"'], [("contact.0.mu", "high")]),
    Case("fields_not_bool", ["output.fields", '"yes"'], [("output.fields", "yes")]),
    Case("bc_is_a_table", ["step.0.bc"], [("step.0.bc", {"on": "block_top"})]),
    # out of range
    Case("E_zero", ["body.1.E", "0"], [("body.1.E", 0)]),
    Case("E_negative", ["body.0.E", "-5.0"], [("body.0.E", -5.0)]),
    Case("nu_half", ["body.0.nu", "0.5"], [("body.0.nu", 0.5)]),
    Case("nu_below_minus_one", ["body.1.nu", "-1.5"], [("body.1.nu", -1.5)]),
    Case("mu_negative", ["contact.0.mu", "-0.1"], [("contact.0.mu", -0.1)]),
    Case("K_zero", ["contact.0.K", "0.0"], [("contact.0.K", 0.0)]),
    Case("K_negative", ["contact.0.K", "-1000.0"], [("contact.0.K", -1000.0)]),
    Case("stick_slope_negative", ["contact.0.stick_slope", "-1000.0"],
         [("contact.0.stick_slope", -1000.0)]),
    Case("stick_slope_zero", ["contact.0.stick_slope", "0"], [("contact.0.stick_slope", 0)]),
    Case("K_unknown_string", ['contact.0.K = "calculx"', '"calculix"'],
         [("contact.0.K", "calculx")]),
    Case("set_stick_slope_unknown_string", ['contact.0.stick_slope = "stiff"', '"calculix"'],
         args=["--set", "contact.0.stick_slope=stiff"]),
    Case("degree_three", ["body.0.degree", "3"], [("body.0.degree", 3)]),
    # missing keys and sections
    Case("missing_E", ["body.0.E", "missing"], [("body.0.E", DELETE)]),
    Case("missing_bc_u", ["step.0.bc.1.u"], [("step.0.bc.1.u", DELETE)]),
    Case("missing_mesh_table", ["mesh", "missing"], [("mesh", DELETE)]),
    Case("no_body", ["body"], [("body", [])]),
    # contact pairs, laws, shapes
    Case("slave_equals_master", ["contact.0.master", "block_bottom"],
         [("contact.0.master", "block_bottom")]),
    Case("unknown_law", ["contact.0.law", "soft"], [("contact.0.law", "soft")]),
    Case("exponential_without_p0", ["contact.0.p0", "exponential"],
         [("contact.0.law", "exponential")]),
    Case("tabular_without_table", ["contact.0.table", "tabular"], [("contact.0.law", "tabular")]),
    Case("unknown_shape", ["rigid.0.shape", "cone"], [("rigid.0.shape", "cone")], base="rigid"),
    Case("plane_without_normal", ["rigid.0.normal"], [("rigid.0.normal", DELETE)], base="rigid"),
    Case("slave_is_rigid", ["contact.0.slave", "floor"],
         [("contact.0.slave", "floor"), ("contact.0.master", "bottom")], base="rigid"),
    Case("unknown_rigid_in_step", ["step.0.rigid.0.name", "wall"],
         [("step.0.rigid.0.name", "wall")], base="rigid"),
    Case("cylinder_in_2d", ["rigid.0.shape", "cylinder"],
         [("rigid.0", {"name": "drum", "shape": "cylinder", "point": [0.5, -0.5],
                       "axis": [0.0, 1.0], "radius": 0.5})], base="planar"),
    # vectors and increments
    Case("u_mixed_lengths", ["step.1.bc.0.u", "2 components"], [("step.1.bc.0.u", [0.05, 0.0])]),
    Case("u_four_components", ["step.0.bc.0.u"], [("step.0.bc.0.u", [0.0, 0.0, 0.0, 0.0])]),
    Case("u_bad_component", ["step.0.bc.1.u.2", "down"], [("step.0.bc.1.u", [0.0, 0.0, "down"])]),
    Case("increments_zero", ["step.0.increments", "0"], [("step.0.increments", 0)]),
    Case("increments_negative", ["step.1.increments", "-3"], [("step.1.increments", -3)]),
    Case("max_cutbacks_negative", ["step.1.max_cutbacks", "-1"], [("step.1.max_cutbacks", -1)]),
    Case("max_iterations_zero", ["step.0.max_iterations", "0"], [("step.0.max_iterations", 0)]),
    Case("newton_rtol_zero", ["step.0.newton_rtol"], [("step.0.newton_rtol", 0.0)]),
    # groups named in the scene
    Case("empty_group_name", ["step.0.bc.0.on", '""'], [("step.0.bc.0.on", "")]),
    Case("group_twice_in_step", ["step.0.bc.1.on", "foundation_bottom"],
         [("step.0.bc.1.on", "foundation_bottom")]),
    Case("traction_and_pressure", ["step.1.load.0", "traction", "pressure"],
         [("step.1.load", [{"on": "block_top", "traction": [0.0, 0.0, -1.0],
                            "pressure": 1.0}])]),
    # files and syntax
    Case("mesh_not_msh", ["mesh.file", "two.stl"], [("mesh.file", "two.stl")]),
    Case("toml_syntax_error", ["case_toml_syntax_error.toml:3", "TOML"],
         text='[mesh]\nfile = "two.msh"\n[[body]\nname = "block"\n'),
    Case("scene_missing", ["no_such_scene.toml", "no such"], scene="{d}/no_such_scene.toml"),
    Case("scene_is_a_directory", ["directory"], scene="{d}", command="run"),
    # --set
    Case("set_without_value", ["--set", "contact.0.mu", "KEY=VALUE"],
         args=["--set", "contact.0.mu"]),
    Case("set_index_out_of_range", ["step.5", "out of range"],
         args=["--set", "step.5.increments=2"]),
    Case("set_not_an_index", ["body.first", "index"], args=["--set", "body.first.E=1"]),
    Case("set_unknown_key", ["contact.0.friction", "unknown key"],
         args=["--set", "contact.0.friction=0.2"]),
    Case("set_bad_value", ["body.0.E", "abc", "number"], args=["--set", "body.0.E=abc"]),
    Case("set_out_of_range", ["contact.0.mu", "-0.2"], args=["--set", "contact.0.mu=-0.2"]),
    Case("set_through_a_number", ["body.0.E", "neither a table nor an array"],
         args=["--set", "body.0.E.x=1"]),
    Case("set_bad_value_run", ["step.1.increments", "many"], command="run",
         args=["--set", "step.1.increments=many", "--out", "{d}/never"]),
    # command line
    Case("unknown_option", ["--frobnicate"], args=["--frobnicate"]),
    Case("unknown_command", ["solve"], command="solve"),
    Case("out_without_value", ["--out"], command="run", args=["--out"]),
    # the scene does not fit the mesh (dolfinx needed)
    Case("bc_on_missing_group", ["step.0.bc.0.on", "nowhere"], [("step.0.bc.0.on", "nowhere")]),
    Case("bc_on_missing_group_run", ["step.1.bc.0.on", "nowhere"], [("step.1.bc.0.on", "nowhere")],
         command="run", args=["--out", "{d}/never"]),
    Case("slave_missing", ["contact.0.slave", "bottom_face"], [("contact.0.slave", "bottom_face")]),
    Case("slave_is_volume", ["contact.0.slave", "block", "dimension"],
         [("contact.0.slave", "block")]),
    Case("master_is_volume", ["contact.0.master", "foundation", "dimension"],
         [("contact.0.master", "foundation")]),
    Case("load_on_edge_3d", ["step.0.load.0.on", "edge_x0y0"],
         [("step.0.load", [{"on": "edge_x0y0", "traction": [0.0, 0.0, -1.0]}])], base="rigid"),
    Case("body_not_in_mesh", ["base", "two.msh"], [("body.1.name", "base")]),
    Case("body_is_a_facet_group", ["foundation_top", "dimension"],
         [("body.1.name", "foundation_top")]),
    Case("reaction_group_missing", ["output.reactions", "nowhere"],
         [("output.reactions", ["block_top", "nowhere"])]),
    Case("u_2d_on_3d_mesh", ["step.0.bc.0.u", "3D"],
         [("step.0.bc.0.u", [0.0, 0.0]), ("step.0.bc.1.u", [0.0, -0.01]),
          ("step.1.bc.0.u", [0.05, -0.01])]),
    Case("u_3d_on_2d_mesh", ["step.0.bc.0.u", "2D"],
         [("step.0.bc.0.u", [0.0, -0.001, 0.0]), ("rigid.0.center", [0.5, -0.5, 0.0])],
         base="planar"),
    Case("conflicting_bcs_check", ["step.0", "'side_x0'", "'top'", "overlap", "component(s) z"],
         [("step.0.bc", [{"on": "top", "u": [0.0, 0.0, -0.01]},
                         {"on": "side_x0", "u": [0.0, 0.0, 0.0]}])], base="rigid"),
    Case("conflicting_bcs_later_step", ["step.1", "'side_x0'", "'top'", "overlap"],
         [("step.1", {"name": "hold", "bc": [{"on": "side_x0", "u": [0.0, 0.0, 0.0]}]})],
         base="rigid", command="run", args=["--out", "{d}/conflict_out", "--quiet"]),
    # meshes
    Case("mesh_file_missing", ["mesh.file", "absent.msh", "no such file"],
         [("mesh.file", "absent.msh")], command="run", args=["--out", "{d}/never"]),
    Case("mesh_corrupt", ["corrupt.msh", "cannot be read"], [("mesh.file", "corrupt.msh")]),
    Case("mesh_truncated", ["truncated.msh"], [("mesh.file", "truncated.msh")]),
    Case("mesh_without_names", ["nonames.msh", "no named physical groups"],
         [("mesh.file", "nonames.msh")]),
    Case("mesh_is_a_geo_script", ["script.msh", "not Gmsh MSH"],
         [("mesh.file", "script.msh")], command="run", args=["--out", "{d}/never"]),
    Case("mesh_is_a_fifo", ["mesh.file", "fifo.msh", "FIFO"], [("mesh.file", "fifo.msh")]),
    Case("mesh_is_dev_zero", ["mesh.file", "/dev/zero", "device"], [("mesh.file", "zero.msh")]),
    Case("mesh_is_a_directory", ["mesh.file", "dir.msh", "directory"],
         [("mesh.file", "dir.msh")]),
    Case("mesh_version_3", ["v3.msh", "not Gmsh MSH 2.2 or 4.1"], [("mesh.file", "v3.msh")]),
    Case("mesh_declares_huge_node_count", ["huge.msh", "1000000000000 nodes"],
         [("mesh.file", "huge.msh")]),
    Case("scene_is_a_fifo", ["fifo.toml", "FIFO"], scene="{d}/fifo.toml"),
    Case("mesh_nan_coordinate", ["rect_nan.msh", "body 'block'", "non-finite"],
         [("mesh.file", "rect_nan.msh")], base="planar"),
    Case("mesh_zero_area_cell", ["rect_flat.msh", "body 'block'", "zero or negative measure"],
         [("mesh.file", "rect_flat.msh")], base="planar"),
    Case("mesh_tangled_cell", ["rect_tangled.msh", "body 'block'", "zero or negative measure"],
         [("mesh.file", "rect_tangled.msh")], base="planar", command="run",
         args=["--out", "{d}/never"]),
    # numbers that overflow or are not finite, nesting, tabular laws
    Case("set_E_inf", ["body.0.E = inf", "finite"], args=["--set", "body.0.E=inf"]),
    Case("set_u_nan", ["step.0.bc.1.u.2 = nan", "finite"], args=["--set", "step.0.bc.1.u.2=nan"]),
    Case("set_mu_1e400", ["contact.0.mu = inf", "finite"], args=["--set", "contact.0.mu=1e400"]),
    Case("increments_1e400", ["step.1.increments = inf", "integer"], command="run",
         text=toml_dumps(GOOD).replace("increments = 3", "increments = 1e400"),
         args=["--out", "{d}/never"]),
    Case("increments_huge_integer", ["step.1.increments", "<= 1000000"], command="run",
         args=["--set", "step.1.increments=1" + "0" * 400, "--out", "{d}/never"]),
    Case("E_huge_integer", ["body.0.E", "finite"], args=["--set", "body.0.E=1" + "0" * 400]),
    Case("E_overflows_default_K", ["body.1.E = 1e+307", "K = 50 E", "overflows"], command="run",
         args=["--set", "body.1.E=1e307", "--out", "{d}/never"]),
    Case("radius_1e400", ["rigid.0.radius = inf", "finite"],
         text=toml_dumps(PLANAR).replace("radius = 0.5", "radius = 1e400")),
    Case("toml_nested_1000_arrays", ["case_toml_nested_1000_arrays.toml", "nested too deeply"],
         text=toml_dumps(GOOD) + "\nx = " + "[" * 1000 + "]" * 1000 + "\n"),
    Case("toml_nested_600_tables", ["nested too deeply"],
         text="x = " + "{a = " * 600 + "1" + "}" * 600 + "\n" + toml_dumps(GOOD)),
    Case("toml_nested_100_arrays", ["output.x.0.0", "nested more than"],
         text=toml_dumps(GOOD) + "\nx = " + "[" * 100 + "]" * 100 + "\n"),
    Case("tabular_negative_pressure", ["contact.0.table.0.0 = -1.0", ">= 0"],
         [("contact.0.law", "tabular"), ("contact.0.table", [[-1.0, 0.0], [10.0, 0.01]])]),
    Case("tabular_decreasing_pressure", ["contact.0.table.2.0 = 5.0", "increase"],
         [("contact.0.law", "tabular"),
          ("contact.0.table", [[0.0, 0.0], [10.0, 0.01], [5.0, 0.02]])]),
    # finite but too large to solve with (the residual norm squares the forces)
    Case("E_1e300", ["body.1.E = 1e+300", "too large"], command="run",
         args=["--set", "body.1.E=1e300", "--out", "{d}/never"]),
    Case("K_1e200", ["contact.0.K = 1e+200", "too large"], [("contact.0.K", 1e200)]),
    Case("stick_slope_1e200", ["contact.0.stick_slope = 1e+200", "too large"],
         [("contact.0.stick_slope", 1e200)]),
    # bodies that nothing holds against rigid motion
    Case("body_not_held", ["body.0", "'block'", "not held", "step 0"],
         [("contact", []), ("step.0.bc.1.u", ["free", "free", "free"]),
          ("step.0.load", [{"on": "block_top", "traction": [0.0, 0.0, -1.0]}]),
          ("step.1.bc.0.u", ["free", "free", "free"])], command="run",
         args=["--out", "{d}/never"]),
    Case("body_on_forced_obstacle_only", ["body.0", "'block'", "not held"],
         [("step.0.bc.0.u", ["free", "free", "free"]),
          ("step.0.rigid.0", {"name": "floor", "force": [0.0, 0.0, 1.0]})], base="rigid"),
    Case("body_freed_in_later_step", ["body.0", "'block'", "not held", "step 1"],
         [("step.1", {"name": "let go", "bc": [{"on": "top", "u": ["free", "free", "free"]}],
                      "rigid": [{"name": "floor", "force": [0.0, 0.0, 0.0]}]})],
         base="rigid"),
    # names that mean two things, groups that are no contact surface
    Case("rigid_named_like_facet_group", ["rigid.0.name", "'side_x0'", "ambiguous"],
         [("rigid.0.name", "side_x0"), ("contact.0.master", "side_x0"),
          ("step.0.rigid.0.name", "side_x0")], base="rigid"),
    Case("rigid_named_like_body", ["rigid.0.name", "'block'", "ambiguous"],
         [("rigid.0.name", "block"), ("contact.0.master", "block"),
          ("step.0.rigid.0.name", "block")], base="rigid"),
    Case("slave_spans_two_bodies", ["contact.0.slave", "both_bottoms", "spans the bodies block, "
                                    "foundation"],
         [("mesh.file", "spanning.msh"), ("contact.0.slave", "both_bottoms")]),
    Case("master_spans_two_bodies", ["contact.0.master", "both_bottoms", "spans"],
         [("mesh.file", "spanning.msh"), ("contact.0.master", "both_bottoms")], command="run",
         args=["--out", "{d}/never"]),
    Case("interior_slave", ["contact.0.slave", "'middle'", "inside body 'block'"],
         [("mesh.file", "split.msh"), ("contact.0.slave", "middle")], base="rigid"),
    Case("interior_master", ["contact.0.master", "'middle'", "inside body 'block'"],
         [("mesh.file", "split.msh"), ("rigid", []), ("step.0.rigid", []),
          ("contact.0.slave", "top"), ("contact.0.master", "middle")], base="rigid"),
    Case("mesh_with_empty_group", ["empty_group", "empty"],
         [("mesh.file", "empty_group.msh"), ("body", [{"name": "block", "E": 1.0, "nu": 0.3}]),
          ("contact", []), ("step", [{"bc": [{"on": "bottom", "u": [0.0, 0.0, 0.0]}]}])]),
    # output directory
    Case("out_in_proc", ["/proc/forbidden"], command="run", args=["--out", "/proc/forbidden"]),
    Case("out_under_a_file", ["a_file/results"], command="run",
         args=["--out", "{d}/a_file/results"]),
    Case("output_dir_under_a_file", ["a_file/out"], [("output.dir", "a_file/out")],
         command="run"),
]


@pytest.fixture(scope="module")
def outcomes(request, workdir):
    """The subprocess of every selected case, started a few at a time on first use."""
    selected = [item.callspec.params["case"] for item in request.session.items
                if getattr(item, "module", None) is request.module
                and "case" in getattr(getattr(item, "callspec", None), "params", {})]
    pool = ThreadPoolExecutor(max_workers=WORKERS)
    futures: dict[str, Future] = {}
    for case in selected:
        futures[case.id] = pool.submit(lambda c=case: cli(*c.argv(workdir), cwd=workdir))
    yield futures
    pool.shutdown(cancel_futures=True)


def test_case_ids_are_distinct():
    ids = [c.id for c in CASES]
    assert len(set(ids)) == len(ids) >= 35


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input_one_line(case, outcomes, workdir):
    out = outcomes[case.id].result(timeout=TIMEOUT)
    assert_one_line_error(out, case.expect)
    assert out.stdout == "", str(out)
    assert not (workdir / "never").exists()


def test_mesh_files_run_no_code(workdir):
    """A .geo script named .msh, and an options script beside a good mesh, run nothing."""
    script = cli("run", workdir / "good.toml", "--set", 'mesh.file="script.msh"',
                 "--out", workdir / "never", cwd=workdir)
    assert_one_line_error(script, ["script.msh"])
    assert not (workdir / "ran_script").exists()
    good = cli("check", workdir / "good.toml", "--set", 'mesh.file="opt.msh"', cwd=workdir)
    assert good.status == 0, str(good)
    assert not (workdir / "ran_opt").exists()


def test_scene_with_byte_order_mark(workdir):
    """A scene saved with a UTF-8 byte-order mark (as some editors do) is read."""
    out = cli("check", workdir / "bom.toml", cwd=workdir)
    assert out.status == 0 and out.stderr == "", str(out)


def test_debug_shows_traceback(workdir):
    """--debug (before or after the command) lets the exception through."""
    scene = workdir / "case_debug.toml"
    scene.write_text(toml_dumps(edited(GOOD, [("body.0.E", -1.0)])))
    for argv in (["--debug", "check", scene], ["check", scene, "--debug"]):
        out = cli(*argv)
        assert out.status != 0 and "Traceback" in out.stderr and "body.0.E" in out.stderr, out


# --------------------------------------------------------------------------- good runs

HISTORY = ["step", "increment", "t", "newton_iterations", "residual", "active", "slipping",
           "wall_s"]
CONTACT_3D = ["step", "increment", "node", "x", "y", "z", "gap", "pressure", "normal_force",
              "tangential_force_x", "tangential_force_y", "tangential_force_z", "slip", "status"]
SUMMARY_KEYS = {"scene", "scene_sha256", "scene_file_sha256", "title", "overrides",
                "package_version", "resolved", "versions", "mpi_ranks", "dofs", "slave_nodes",
                "increments", "cutbacks", "newton_iterations", "wall_time_s",
                "wall_time_per_phase_s", "converged", "linear_solves", "peak_memory_mib"}
PHASES = {"setup", "contact_search", "contact_assembly", "bulk_assembly", "linear_solve",
          "output"}


def read_csv(path: Path) -> tuple[list[str], list[dict[str, str]]]:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    assert all(len(r) == len(header) for r in body), path
    return header, [dict(zip(header, r)) for r in body]


def assert_same_history(rows: list[dict], serial_rows: list[dict], prefixes=("R_", "U_", "F_"),
                        rtol: float = 1e-8) -> None:
    """Same increments, and the columns starting with ``prefixes`` equal to ``rtol``
    relative; components that (nearly) vanish, below 1e-3 of the largest value of their
    kind, are compared relative to 1e-3 of it instead (round-off of the large ones)."""
    assert [(r["step"], r["increment"]) for r in rows] == \
        [(r["step"], r["increment"]) for r in serial_rows]
    for prefix in prefixes:
        columns = [c for c in serial_rows[0] if c.startswith(prefix)]
        if not columns:
            continue
        scale = max(abs(float(r[c])) for r in serial_rows for c in columns)
        for row, ref in zip(rows, serial_rows):
            for c in columns:
                a, b = float(row[c]), float(ref[c])
                assert abs(a - b) <= rtol * max(abs(b), 1e-3 * scale), \
                    (row["step"], row["increment"], c, a, b)


def increments_of(rows: list[dict[str, str]]) -> list[tuple[int, int]]:
    seen: dict[tuple[int, int], None] = {}
    for r in rows:
        seen[(int(r["step"]), int(r["increment"]))] = None
    return list(seen)


def axes(prefix: str, name: str) -> list[str]:
    return [f"{prefix}_{name}_{a}" for a in "xyz"]


@pytest.fixture(scope="module")
def good_run(workdir) -> tuple[Outcome, Path]:
    out_dir = workdir / "good_out"
    return cli("run", workdir / "good.toml", "--out", out_dir), out_dir


def test_check_good_scene(workdir):
    out = cli("check", workdir / "good.toml")
    assert out.status == 0, str(out)
    assert len(out.stdout.splitlines()) == 1 and "ok" in out.stdout, str(out)
    assert out.stderr == "", str(out)


def test_run_good_scene(good_run):
    out, d = good_run
    assert out.status == 0, str(out)
    assert out.stderr == "", str(out)
    assert "Traceback" not in out.stdout
    # default reactions: every group carrying a bc, in order of first appearance
    header, rows = read_csv(d / "history.csv")
    assert header == HISTORY + axes("R", "foundation_bottom") + axes("R", "block_top")
    assert [(int(r["step"]), int(r["increment"])) for r in rows] == [(0, 1), (1, 1), (1, 2),
                                                                     (1, 3)]
    assert [float(r["t"]) for r in rows] == pytest.approx([1.0, 4 / 3, 5 / 3, 2.0])
    for r in rows:  # the reactions of the two supports balance
        for a in "xyz":
            total = float(r[f"R_block_top_{a}"]) + float(r[f"R_foundation_bottom_{a}"])
            assert abs(total) <= 1e-6 * abs(float(rows[0]["R_block_top_z"]))
    assert float(rows[0]["R_block_top_z"]) < 0  # the constraint pushes the block down
    cheader, crows = read_csv(d / "contact.csv")
    assert cheader == CONTACT_3D
    assert increments_of(crows) == increments_of(rows)
    assert {r["status"] for r in crows} <= {"open", "stick", "slip"}
    summary = json.loads((d / "summary.json").read_text())
    assert SUMMARY_KEYS <= set(summary), set(summary)
    assert PHASES <= set(summary["wall_time_per_phase_s"])
    assert summary["converged"] is True and summary["increments"] == 4
    assert summary["mpi_ranks"] == 1 and summary["slave_nodes"] == 9
    # progress: (at least) one line per increment
    assert len(out.stdout.splitlines()) >= 4, str(out)


def test_run_rigid_columns(workdir):
    d = workdir / "rigid_out"
    out = cli("run", workdir / "rigid.toml", "--out", d)
    assert out.status == 0, str(out)
    header, rows = read_csv(d / "history.csv")
    assert header == (HISTORY + axes("R", "top") + axes("U", "floor") + axes("F", "floor")
                      + axes("M", "floor"))
    assert len(rows) == 2
    last = rows[-1]
    # the floor holds the block: its force balances the reaction on the top
    assert float(last["F_floor_z"]) == pytest.approx(-float(last["R_top_z"]), rel=1e-6)
    # its moment about its point (the origin): the block [0, 1]^2 presses it symmetrically
    # about (0.5, 0.5), so M = (0.5, -0.5, 0) F_z
    F_z = float(last["F_floor_z"])
    assert float(last["M_floor_x"]) == pytest.approx(0.5 * F_z, rel=1e-6)
    assert float(last["M_floor_y"]) == pytest.approx(-0.5 * F_z, rel=1e-6)
    assert abs(float(last["M_floor_z"])) < 1e-9 * abs(F_z)
    assert all(float(last[f"U_floor_{a}"]) == 0.0 for a in "xyz")
    cheader, _ = read_csv(d / "contact.csv")
    assert cheader == CONTACT_3D


def test_diverging_run(workdir):
    d = workdir / "diverged_out"
    out = cli("run", workdir / "good.toml", "--out", d, "--quiet",
              "--set", "step.1.max_iterations=1", "--set", "step.1.max_cutbacks=0")
    line = assert_one_line_error(out, ["step 1", "increment 1", "converge"], EXIT_DIVERGED)
    assert "slide" in line
    summary = json.loads((d / "summary.json").read_text())
    assert summary["converged"] is False
    _, rows = read_csv(d / "history.csv")
    assert [(int(r["step"]), int(r["increment"])) for r in rows] == [(0, 1)]
    _, crows = read_csv(d / "contact.csv")
    assert increments_of(crows) == [(0, 1)]


def test_tiny_normal_is_a_direction(workdir):
    """A rigid plane whose normal is [0, 0, 1e-200] (its norm underflows) is the plane of
    normal [0, 0, 1]: the same reactions, and nothing on stderr (no numpy warnings)."""
    results = []
    for name, normal in (("unit", 1.0), ("tiny", 1e-200)):
        scene = workdir / f"case_normal_{name}.toml"
        scene.write_text(toml_dumps(edited(RIGID, [("rigid.0.normal", [0.0, 0.0, normal])])))
        out = cli("run", scene, "--out", workdir / f"normal_{name}", "--quiet")
        assert out.status == 0 and out.stderr == "", str(out)
        results.append(read_csv(workdir / f"normal_{name}" / "history.csv")[1])
    assert float(results[0][-1]["F_floor_z"]) > 0
    assert_same_history(results[1], results[0], rtol=1e-12)


def test_singular_jacobian_one_line(workdir):
    """A block that only the floor holds, pulled off it: exit 3, one line naming the step,
    the increment and the singular Jacobian; the press is kept."""
    scene = workdir / "case_pulled_off.toml"
    scene.write_text(toml_dumps(edited(RIGID, [("step.1", {
        "name": "pull", "max_cutbacks": 1, "bc": [{"on": "top", "u": ["free"] * 3}],
        "load": [{"on": "top", "traction": [0.0, 0.0, 10.0]}]})])))
    d = workdir / "pulled_off_out"
    out = cli("run", scene, "--out", d, "--quiet")
    assert_one_line_error(out, ["step 1", "increment 1", "singular Jacobian"], EXIT_DIVERGED)
    _, rows = read_csv(d / "history.csv")
    assert [(r["step"], r["increment"]) for r in rows] == [("0", "1"), ("0", "2")]


def test_rigid_drift_one_line(workdir):
    """A block on a frictionless floor whose top is held in y and z only: nothing holds it
    along x, and its first converged increment (any sideways drift balances) stops the run
    with exit 2 and one line naming the body and the motion; nothing is written as a
    result."""
    scene = workdir / "case_drift.toml"
    scene.write_text(toml_dumps(edited(RIGID, [("contact.0.mu", 0.0),
                                               ("step.0.bc.0.u", ["free", 0.0, -0.01])])))
    d = workdir / "drift_out"
    out = cli("run", scene, "--out", d, "--quiet")
    assert_one_line_error(out, ["body 'block' can move rigidly (translation along (1, 0, 0))"
                                " with nothing to hold it"])
    _, rows = read_csv(d / "history.csv")
    assert rows == []


def test_rerun_replaces_results(workdir):
    d = workdir / "rerun_out"
    first = cli("run", workdir / "good.toml", "--out", d, "--set", "step.1.increments=3")
    assert first.status == 0 and first.stderr == "", str(first)
    second = cli("run", workdir / "good.toml", "--out", d, "--set", "step.1.increments=2",
                 "--set", "contact.0.mu=0.1")
    assert second.status == 0, str(second)
    assert len(second.stderr.splitlines()) == 1 and str(d) in second.stderr, str(second)
    assert "Traceback" not in second.stderr
    _, rows = read_csv(d / "history.csv")
    assert [(int(r["step"]), int(r["increment"])) for r in rows] == [(0, 1), (1, 1), (1, 2)]
    _, crows = read_csv(d / "contact.csv")
    assert increments_of(crows) == [(0, 1), (1, 1), (1, 2)]
    assert json.loads((d / "summary.json").read_text())["increments"] == 3
    # --quiet: nothing on stdout, and the rerun is not announced either
    third = cli("run", workdir / "good.toml", "--out", d, "--quiet")
    assert third.status == 0, str(third)
    assert third.stdout == "" and third.stderr == "", str(third)
    _, rows = read_csv(d / "history.csv")
    assert len(rows) == 4


# --------------------------------------------------------------------------- mpirun

def mpirun_cli(ranks: int, *args: Any) -> Outcome:
    """The command line under ``mpirun -n ranks`` (oversubscribed)."""
    from dolfinx_friction import _compat as compat  # Open MPI 4 (Debian 12) / 5 (Debian 13) launchers
    command = [*compat.mpirun_command(ranks), sys.executable, "-m", "dolfinx_friction",
               *map(str, args)]
    env = compat.mpirun_environment(cli_env())
    proc = subprocess.run(command, capture_output=True, text=True, env=env, timeout=TIMEOUT)
    return Outcome(command, proc.returncode, proc.stdout, compat.mpirun_stderr(proc.stderr))


@pytest.mark.skipif(shutil.which("mpirun") is None, reason="mpirun not found")
def test_mpirun_matches_serial(workdir, good_run):
    # a bad scene: one line, from rank 0 only
    bad = workdir / "case_mpi_bad.toml"
    bad.write_text(toml_dumps(edited(GOOD, [("step.0.bc.1.on", "nowhere")])))
    assert_one_line_error(mpirun_cli(2, "run", bad, "--out", workdir / "never"),
                          ["step.0.bc.1.on", "nowhere"])
    # a good scene: the same results as the serial run
    d = workdir / "mpi_out"
    out = mpirun_cli(2, "run", workdir / "good.toml", "--out", d, "--quiet")
    assert out.status == 0 and out.stdout == "" and out.stderr == "", str(out)
    serial_out, serial_dir = good_run
    assert serial_out.status == 0, str(serial_out)
    header, rows = read_csv(d / "history.csv")
    serial_header, serial_rows = read_csv(serial_dir / "history.csv")
    assert header == serial_header
    assert len(rows) == len(serial_rows)
    assert_same_history(rows, serial_rows, ("R_",))
    assert json.loads((d / "summary.json").read_text())["mpi_ranks"] == 2
    _, crows = read_csv(d / "contact.csv")
    _, serial_crows = read_csv(serial_dir / "contact.csv")
    assert [(r["step"], r["increment"], r["node"], r["status"]) for r in crows] == \
        [(r["step"], r["increment"], r["node"], r["status"]) for r in serial_crows]


MPI_CASES = ["mesh_is_a_geo_script", "mesh_tangled_cell", "mesh_nan_coordinate",
             "slave_spans_two_bodies", "interior_slave", "rigid_named_like_facet_group",
             "E_1e300", "body_not_held"]


@pytest.mark.skipif(shutil.which("mpirun") is None, reason="mpirun not found")
@pytest.mark.parametrize("case_id", MPI_CASES)
def test_bad_input_one_line_under_mpirun(workdir, case_id):
    """Mesh and group checks that are collective: one line from rank 0, exit 2 on 2 ranks."""
    case = next(c for c in CASES if c.id == case_id)
    out = mpirun_cli(2, *case.argv(workdir))
    assert_one_line_error(out, case.expect)
    assert not (workdir / "never").exists() and not (workdir / "ran_script").exists()


def test_singleton_settings_only_without_a_launcher():
    """A process no launcher started gets Open MPI's singleton settings where the user set
    none (the user's own choice stays); under a launcher none."""
    from dolfinx_friction.cli import mpi
    assert mpi.singleton_settings({}) == mpi.SINGLETON
    assert mpi.singleton_settings({"OMPI_MCA_pml": "ucx"}) == {
        k: v for k, v in mpi.SINGLETON.items() if k != "OMPI_MCA_pml"}
    assert mpi.singleton_settings({"OMPI_COMM_WORLD_RANK": "0"}) == {}


def test_singleton_settings_leave_with_mpi_started():
    """MPI is started by the command line (its modules import no mpi4py before) with the
    singleton's settings (self transport only), which leave the environment again: an
    mpirun started from that process runs ranks that talk to each other (with the settings
    inherited they found no transport)."""
    from dolfinx_friction.cli import mpi
    env = {k: v for k, v in cli_env().items() if k not in (*mpi.SINGLETON, *mpi.LAUNCHER_RANKS)}
    child = ("from mpi4py import MPI; c = MPI.COMM_WORLD; s = c.gather(c.allreduce(c.rank + 1))\n"
             "if c.rank == 0: print(*s, sep=',')")  # one line: the ranks' prints interleave
    script = (
        "import os, subprocess, sys\n"
        "from dolfinx_friction.cli import frontend, mpi, worker\n"
        "assert 'mpi4py.MPI' not in sys.modules and mpi.start().COMM_WORLD.size == 1\n"
        "from dolfinx_friction import _compat as compat\n"
        "print(sorted(set(mpi.SINGLETON) & set(os.environ)))\n"
        f"cmd = [*compat.mpirun_command(2), sys.executable, '-c', {child!r}]\n"
        "out = subprocess.run(cmd, env=compat.mpirun_environment(dict(os.environ)),\n"
        "                     capture_output=True, text=True, timeout=120)\n"
        "print(out.stdout.split(), out.returncode)\n")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          env=env, timeout=TIMEOUT)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines() == ["[]", "['3,3'] 0"], proc.stdout + proc.stderr


def test_numpy_starts_without_huge_page_advice():
    """The command line sets numpy's ``NUMPY_MADVISE_HUGEPAGE=0`` before anything imports
    numpy (its modules import none before ``main``; numpy reads it once, at import), and
    keeps a value the user set."""
    from dolfinx_friction.cli import environment
    env = {k: v for k, v in cli_env().items() if k not in environment.NUMPY}
    script = (
        "import os, sys\n"
        "from dolfinx_friction.cli import frontend\n"
        "assert 'numpy' not in sys.modules\n"
        f"status = frontend.main(['check', {str(ROOT / 'demos' / 'incline.toml')!r}])\n"
        "assert 'numpy' in sys.modules\n"
        "print(status, os.environ['NUMPY_MADVISE_HUGEPAGE'])\n")
    for given, expected in ((None, "0"), ("1", "1")):
        proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                              env={**env, **({} if given is None else
                                             {"NUMPY_MADVISE_HUGEPAGE": given})},
                              timeout=TIMEOUT)
        assert proc.returncode == 0, proc.stderr
        assert proc.stdout.split()[-2:] == ["0", expected], proc.stdout + proc.stderr
