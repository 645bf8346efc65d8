"""What a run leaves and shows, through the command line: the fields as one time series
per body, the provenance in summary.json, the progress on a terminal or not, --version.

A block pressed onto a foundation and slid (3D, 4 increments, fields on) runs serially and
under ``mpirun -n 2``.  The time series ``fields/<body>.xdmf`` must list exactly the
increments of history.csv at their pseudo-time, refer only to datasets that exist (the
ones the per-increment files refer to), and, read by VTK's XDMF reader, give the prescribed
displacement of the block's top at every time.  Started from a serial pytest only.
"""
from __future__ import annotations

import errno
import fcntl
import hashlib
import json
import os
import pty
import re
import shutil
import struct
import subprocess
import sys
import termios
import threading
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

import dolfinx_friction
from dolfinx_friction.nls.defaults import factorisation
from dolfinx_friction.contact.laws import Linear
from dolfinx_friction.reference import meshes
from dolfinx_friction.reference.cases import block_on_foundation_toml
from tests.cli.test_cli import TIMEOUT, cli, cli_env, mpirun_cli, read_csv

pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1,
                                reason="runs the command line from a serial pytest")

HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
BODIES = ("block", "foundation")
FIELDS = {"displacement", "contact_pressure", "tangential_traction", "slip", "status",
          "cauchy_stress", "von_mises"}
SLIDE, PRESS = 0.2, -0.01  # the block's top: pressed by 0.01, then slid 0.2 along x
SCENE = block_on_foundation_toml("two.msh", press=PRESS, slide=SLIDE)
OVERRIDES = ("--set", "contact.0.mu=0.2", "--set", "step.1.increments=3")


@pytest.fixture(scope="module")
def scene(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("outputs")
    meshes.two_boxes(d / "two.msh", n_block=(2, 2, 1), n_foundation=(3, 3, 1))
    (d / "scene.toml").write_text(SCENE)
    return d / "scene.toml"


@pytest.fixture(scope="module")
def serial(scene):
    out = scene.parent / "serial"
    return cli("run", scene, "--out", out, *OVERRIDES), out


@pytest.fixture(scope="module")
def two_ranks(scene):
    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not found")
    out = scene.parent / "two_ranks"
    return mpirun_cli(2, "run", scene, "--out", out, "--quiet", *OVERRIDES), out


def _history(out: Path) -> list[dict[str, str]]:
    return read_csv(out / "history.csv")[1]


def _folder(row: dict[str, str]) -> str:
    return f"step{row['step']}_increment{int(row['increment']):04d}"


def _hdf_items(root: ET.Element) -> list[str]:
    return [i.text.strip() for i in root.iter("DataItem") if i.get("Format") == "HDF"]


def series_grids(fields: Path, body: str) -> list[ET.Element]:
    """The grids of a body's time series, checked to be a temporal collection whose every
    dataset is one that the increment's own file refers to, in a complete folder."""
    root = ET.parse(fields / f"{body}.xdmf").getroot()
    collections = [g for g in root.iter("Grid") if g.get("GridType") == "Collection"]
    assert len(collections) == 1 and collections[0].get("CollectionType") == "Temporal"
    grids = collections[0].findall("Grid")
    for grid in grids:
        folder = fields / grid.get("Name")
        own = set(_hdf_items(ET.parse(folder / f"{body}.xdmf").getroot()))
        for item in _hdf_items(grid):
            file, dataset = item.split(":", 1)
            assert file == f"{folder.name}/{body}.h5", item
            assert (fields / file).read_bytes()[:8] == HDF5_SIGNATURE, item
            assert f"{body}.h5:{dataset}" in own, item
        assert {a.get("Name") for a in grid.iter("Attribute")} == FIELDS
    return grids


def assert_series_match_history(out: Path) -> None:
    history = _history(out)
    for body in BODIES:
        grids = series_grids(out / "fields", body)
        assert [g.get("Name") for g in grids] == [_folder(r) for r in history]
        assert [float(g.find("Time").get("Value")) for g in grids] == \
            [float(r["t"]) for r in history]


def test_time_series_lists_the_increments(serial):
    outcome, out = serial
    assert outcome.status == 0, str(outcome)
    assert len(_history(out)) == 4
    assert_series_match_history(out)


def test_time_series_on_two_ranks(two_ranks, serial):
    outcome, out = two_ranks
    assert outcome.status == 0 and outcome.stdout == "" and outcome.stderr == "", str(outcome)
    assert_series_match_history(out)
    assert [r["t"] for r in _history(out)] == [r["t"] for r in _history(serial[1])]


def _top_displacements(path: Path) -> tuple[list[float], list[np.ndarray]]:
    """VTK's XDMF reader on a body's time series: the times, and per time the displacement
    of the nodes on the body's top (largest z)."""
    vtk = pytest.importorskip("vtkmodules.vtkIOXdmf2")
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline
    reader = vtk.vtkXdmfReader()
    reader.SetFileName(str(path))
    reader.UpdateInformation()
    times = list(reader.GetOutputInformation(0).Get(vtkStreamingDemandDrivenPipeline
                                                    .TIME_STEPS()))
    tops = []
    for t in times:
        reader.UpdateTimeStep(t)
        grid = reader.GetOutputDataObject(0)
        x = vtk_to_numpy(grid.GetPoints().GetData())
        u = vtk_to_numpy(grid.GetPointData().GetArray("displacement"))
        tops.append(u[np.isclose(x[:, 2], x[:, 2].max())])
    return times, tops


@pytest.mark.parametrize("run", ["serial", "two_ranks"])
def test_time_series_read_by_vtk(run, request):
    """One dataset with a time step per increment; the top of the block moves as
    prescribed: (0, 0, -0.01) at t = 1, then (0.2 (t - 1), 0, -0.01)."""
    outcome, out = request.getfixturevalue(run)
    assert outcome.status == 0, str(outcome)
    times, tops = _top_displacements(out / "fields" / "block.xdmf")
    assert times == [float(r["t"]) for r in _history(out)]
    for t, u in zip(times, tops):
        assert len(u) == 9
        want = np.array([SLIDE * (t - 1.0), 0.0, PRESS])
        assert np.abs(u - want).max() <= 1e-7, (t, u)  # (stored in single precision)


# --------------------------------------------------------------------------- provenance

def _canonical_sha256(data) -> str:
    text = json.dumps(data, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def test_summary_records_the_scene_as_run(serial, scene):
    outcome, out = serial
    summary = json.loads((out / "summary.json").read_text())
    assert summary["title"] == "block slid on a foundation"
    assert summary["overrides"] == ["contact.0.mu=0.2", "step.1.increments=3"]
    assert summary["package_version"] == dolfinx_friction.__version__
    assert summary["scene_file_sha256"] == hashlib.sha256(scene.read_bytes()).hexdigest()
    resolved = summary["resolved"]
    assert summary["scene_sha256"] == _canonical_sha256(resolved)
    assert [b["degree"] for b in resolved["bodies"]] == [1, 1]
    assert [(b["model"], b["E"], b["nu"]) for b in resolved["bodies"]] == \
        [("linear", 1000.0, 0.3)] * 2
    (pair,) = resolved["contacts"]
    assert pair["mu"] == 0.2 and pair["law"] == "linear"  # the override, not the file
    assert pair["tangent"] == "consistent" and pair["pairing_iterations"] >= 1
    assert pair["stick_slope"] > 0 and 0 < pair["c0"] < 1
    assert resolved["steps"][1]["increments"] == 3
    assert resolved["linear_solver"]["pc_type"] == "lu"
    # the serial run's package by the auto rule (this 3D scene: PETSc's own below 400 dofs)
    assert resolved["linear_solver"]["factor_solver_type"] == factorisation(
        resolved["solver"]["dofs"], 3, 1)
    assert resolved["mesh"]["sha256"] == \
        hashlib.sha256((scene.parent / "two.msh").read_bytes()).hexdigest()
    # the K and sigma_inf recorded are those the contact used: the pressures of contact.csv
    law = Linear(pair["K"], pair["sigma_inf"], pair["c0"])
    rows = [r for r in read_csv(out / "contact.csv")[1] if r["status"] != "open"]
    assert rows
    gap = np.array([float(r["gap"]) for r in rows])
    pressure = np.array([float(r["pressure"]) for r in rows])
    assert np.allclose(pressure, law.pressure(-gap)[0], rtol=1e-9, atol=0.0)


def test_scene_hash_is_of_the_scene_as_run(serial, two_ranks, scene):
    """Two ranks ran the same scene, with the solver the rank count allows (this small
    system: PETSc's own LU serially, MUMPS on two ranks): the resolved scenes differ only
    in ``linear_solver``, and the hashes as they do; another override is another scene."""
    summaries = [json.loads((r[1] / "summary.json").read_text()) for r in (serial, two_ranks)]
    solvers = [s["resolved"].pop("linear_solver") for s in summaries]
    assert summaries[0]["resolved"] == summaries[1]["resolved"]
    assert [s["factor_solver_type"] for s in solvers] == [
        factorisation(summaries[0]["resolved"]["solver"]["dofs"], 3, ranks) for ranks in (1, 2)]
    assert (summaries[0]["scene_sha256"] == summaries[1]["scene_sha256"]) == \
        (solvers[0] == solvers[1])
    out = scene.parent / "other"
    rerun = cli("run", scene, "--out", out, "--quiet", "--set", "output.fields=false")
    assert rerun.status == 0, str(rerun)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["overrides"] == ["output.fields=false"]
    assert summary["scene_file_sha256"] == summaries[0]["scene_file_sha256"]
    assert summary["scene_sha256"] != summaries[0]["scene_sha256"]
    assert summary["resolved"]["contacts"][0]["mu"] == 0.3


# --------------------------------------------------------------------------- progress

LINE = re.compile(r"step (\d) \((\w+)\) increment (\d+): t = [\d.]+, \d+ Newton iterations, "
                  r"residual \S+, \d+ in contact, \d+ slipping")


def test_progress_lines_when_not_a_terminal(serial):
    outcome, out = serial
    lines = outcome.stdout.splitlines()
    assert [LINE.fullmatch(line).group(1, 3) for line in lines[:-1]] == \
        [(r["step"], r["increment"]) for r in _history(out)]
    assert lines[-1].startswith("done: 4 increments")
    assert outcome.stderr == "" and "\r" not in outcome.stdout


def _on_terminal(*args) -> tuple[int, str]:
    """The command line with its standard output on a pseudo-terminal (100 columns);
    (exit status, what the terminal got)."""
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 30, 100, 0, 0))
    proc = subprocess.Popen([sys.executable, "-m", "dolfinx_friction", *map(str, args)],
                            stdout=slave, stderr=subprocess.PIPE, env=cli_env())
    os.close(slave)
    chunks: list[bytes] = []

    def drain():
        while True:
            try:
                data = os.read(master, 4096)
            except OSError as exc:  # EIO: the process closed the terminal
                assert exc.errno == errno.EIO
                return
            if not data:
                return
            chunks.append(data)
    reader = threading.Thread(target=drain, daemon=True)
    reader.start()
    try:
        _, stderr = proc.communicate(timeout=TIMEOUT)
    finally:
        if proc.poll() is None:
            proc.kill()
    reader.join(timeout=10)
    os.close(master)
    assert stderr == b"", stderr
    return proc.returncode, b"".join(chunks).decode()


def test_progress_bar_on_a_terminal(scene):
    status, text = _on_terminal("run", scene, "--out", scene.parent / "tty", *OVERRIDES)
    assert status == 0, text
    assert not LINE.search(text), text  # no plain lines
    frames = [f.strip() for f in re.split(r"[\r\n]+", text) if f.strip()]
    bars = [f for f in frames if f.startswith("step ")]
    # a bar per step, redrawn at every increment: share of the step, time spent and left,
    # the increment, t, Newton iterations
    bar = re.compile(r"step (\d) \((\w+)\):\s+(\d+)%\|.*\| \[\d\d:\d\d<(\d\d:\d\d|\?)"
                     r"(?:, increment (\d+), t = ([\d.]+), (\d+) Newton iterations)?\]")
    parsed = [bar.fullmatch(f) for f in bars]
    assert all(parsed), bars
    seen = {(m.group(1), m.group(5), m.group(3)) for m in parsed if m.group(5)}
    assert {("0", "1", "100"), ("1", "1", "33"), ("1", "2", "67"), ("1", "3", "100")} <= seen
    assert frames[-1].startswith("done: 4 increments")


def test_quiet_shows_nothing_on_a_terminal(scene):
    status, text = _on_terminal("run", scene, "--out", scene.parent / "tty_quiet", "--quiet")
    assert status == 0 and text == "", text


# --------------------------------------------------------------------------- --version

def test_version_before_any_heavy_import():
    proc = subprocess.run([sys.executable, "-X", "importtime", "-m", "dolfinx_friction",
                           "--version"], capture_output=True, text=True, env=cli_env(),
                          timeout=60)
    assert proc.returncode == 0
    assert proc.stdout == f"dolfinx-friction {dolfinx_friction.__version__}\n"
    imported = {line.rsplit("|", 1)[-1].strip() for line in proc.stderr.splitlines()}
    assert not imported & {"mpi4py", "dolfinx", "petsc4py", "numpy", "ufl"}, imported
