"""``dolfinx-friction sweep | plot | render`` through subprocesses, on the tiny scenes of
test_cli: a 2 x 2 sweep (two points diverge) checked against each point's own files, bad
input answered by one line (exit 2) before anything runs, charts and pictures written as
PNG files from a run, a sweep, a run on 2 ranks and a run killed half-way.

Like test_cli, everything here runs from a serial pytest only (under ``mpirun`` the module
is skipped; one test launches ``mpirun -n 2`` itself).  The render tests need VTK's XDMF
reader and an off-screen window (EGL, or an X server): they skip where a probe cannot
draw (Debian 13's VTK renders through X only: run them under ``xvfb-run``).
"""
from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from dolfinx_friction.reference import meshes
from tests.cli.test_cli import (GOOD, _PYCACHE, Outcome, assert_one_line_error, cli, cli_env,
                                edited, mpirun_cli, read_csv, toml_dumps)

pytestmark = pytest.mark.skipif(
    MPI.COMM_WORLD.size > 1,
    reason="the CLI is tested through subprocesses from a serial pytest")

PNG = b"\x89PNG\r\n\x1a\n"
#: Base scene of the sweep: no cutbacks, so that max_iterations = 1 fails in step 1.
SWEPT = edited(GOOD, [("step.1.max_cutbacks", 0)])
SWEEP = ["--set", "step.1.max_iterations=1,30", "--set", "contact.0.mu=0.1,0.3"]


@pytest.fixture(scope="module")
def workdir(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("studies")
    _PYCACHE[:] = [tmp_path_factory.getbasetemp() / "cli_pycache"]
    meshes.two_boxes(d / "two.msh", n_block=(2, 2, 1), n_foundation=(3, 3, 1))
    (d / "swept.toml").write_text(toml_dumps(SWEPT))
    (d / "fields.toml").write_text(toml_dumps(edited(GOOD, [("output.fields", True)])))
    return d


def assert_png(path: Path) -> None:
    assert path.is_file(), path
    data = path.read_bytes()
    assert len(data) > 1000 and data.startswith(PNG), path


# ------------------------------------------------------------------------------ sweep
@pytest.fixture(scope="module")
def sweep(workdir) -> tuple[Outcome, Path]:
    out = workdir / "sweep"
    return cli("sweep", workdir / "swept.toml", *SWEEP, "-j", "2", "--out", out), out


def test_sweep_table_matches_each_point(sweep):
    out, d = sweep
    # two points diverge: the sweep goes on, says so in one line, exits 3
    assert_one_line_error(out, ["2 of 4 points failed", "sweep.csv"], status=3)
    assert "[4/4]" in out.stdout, str(out)
    header, rows = read_csv(d / "sweep.csv")
    assert header[:4] == ["point", "folder", "step.1.max_iterations", "contact.0.mu"]
    assert header[-1] == "reason"
    assert [(r["step.1.max_iterations"], r["contact.0.mu"]) for r in rows] == \
        [("1", "0.1"), ("1", "0.3"), ("30", "0.1"), ("30", "0.3")]  # the first key slowest
    for row in rows:
        folder = d / row["folder"]
        assert folder.name == f"step.1.max_iterations={row['step.1.max_iterations']}," \
                              f"contact.0.mu={row['contact.0.mu']}"
        _, history = read_csv(folder / "history.csv")
        summary = json.loads((folder / "summary.json").read_text())
        last = history[-1]
        forces = [c for c in header if c.startswith("R_")]
        assert len(forces) == 6
        assert {c: row[c] for c in forces} == {c: last[c] for c in forces}
        assert row["t"] == last["t"]
        assert int(row["increments"]) == summary["increments"] == len(history)
        assert int(row["newton_iterations"]) == summary["newton_iterations"]
        assert int(row["cutbacks"]) == summary["cutbacks"]
        assert float(row["wall_s"]) > summary["wall_time_s"]  # the process, start-up included
        if row["step.1.max_iterations"] == "30":
            assert row["converged"] == "true" and row["exit_status"] == "0"
            assert row["reason"] == "" and summary["converged"] is True
            assert len(history) == 4
            assert int(row["newton_iterations"]) == \
                sum(int(h["newton_iterations"]) for h in history)
        else:  # failed: a row all the same, with the run's one-line reason
            assert row["converged"] == "false" and row["exit_status"] == "3"
            assert "step 1" in row["reason"] and "converge" in row["reason"]
            assert summary["converged"] is False and len(history) == 1
    # the friction coefficient shows in the final tangential reaction of the converged points
    done = [r for r in rows if r["converged"] == "true"]
    assert abs(float(done[0]["R_block_top_x"])) < abs(float(done[1]["R_block_top_x"]))


def test_sweep_points_equal_fresh_runs(sweep, workdir):
    """Every point of the sweep ran in a warm worker, after other points: its history.csv
    and contact.csv equal, digit for digit (wall times aside), those of a fresh `run` of
    the same point, a converged one and a failed one (exit 3)."""
    _, d = sweep
    for folder, sets, status in (("step.1.max_iterations=30,contact.0.mu=0.3",
                                  ["step.1.max_iterations=30", "contact.0.mu=0.3"], 0),
                                 ("step.1.max_iterations=1,contact.0.mu=0.3",
                                  ["step.1.max_iterations=1", "contact.0.mu=0.3"], 3)):
        fresh = workdir / f"fresh_{status}"
        args = [arg for value in sets for arg in ("--set", value)]
        assert cli("run", workdir / "swept.toml", "--out", fresh, "--quiet", *args).status \
            == status
        for name in ("history.csv", "contact.csv"):
            _, ours = read_csv(d / folder / name)
            _, theirs = read_csv(fresh / name)
            assert [{k: v for k, v in r.items() if k != "wall_s"} for r in ours] == \
                [{k: v for k, v in r.items() if k != "wall_s"} for r in theirs], name


def test_sweep_writes_no_partial_table(sweep):
    _, d = sweep
    assert sorted(p.name for p in d.iterdir() if p.name.startswith(".")) == []


@pytest.mark.parametrize("args, expect", [
    (["--set", "contact.0.muu=0.1,0.2"], ["contact.0.muu"]),
    (["--set", "contact.3.mu=0.1,0.2"], ["contact.3", "out of range"]),
    (["--set", "contact.0.mu="], ["contact.0.mu", "no values"]),
    (["--set", "contact.0.mu=0.1,,0.2"], ["contact.0.mu", "empty value"]),
    (["--set", "contact.0.mu=0.1,-0.5"], ["contact.0.mu", "-0.5"]),  # one bad point
    (["--set", "contact.0.mu=0.1,0.1"], ["contact.0.mu", "twice"]),
    (["--set", "contact.0.mu=0.1", "--set", "contact.0.mu=0.2"], ["contact.0.mu", "twice"]),
    (["--set", "step.1.bc.0.u=[0.05,0,-0.01],[0.1,0"], ["step.1.bc.0.u", "unclosed"]),
    (["--set", "step.1.bc.0.u=[0.05,0],[0.1,0,0]"], ["step.1.bc.0.u"]),  # 2 components in 3D
    (["--set", "contact.0.mu=0.1", "-j", "0"], ["-j", "at least 1"]),
    ([], ["--set"]),
])
def test_sweep_bad_input_one_line(workdir, args, expect):
    out_dir = workdir / "never"
    out = cli("sweep", workdir / "swept.toml", *args, "--out", out_dir)
    assert_one_line_error(out, expect)
    assert out.stdout == "" and not out_dir.exists()  # nothing launched


def test_sweep_bad_scene_and_mpirun_one_line(workdir):
    assert_one_line_error(cli("sweep", workdir / "missing.toml", "--set", "contact.0.mu=0.1"),
                          ["missing.toml", "no such scene file"])
    env = dict(cli_env(), OMPI_COMM_WORLD_SIZE="2")  # as mpirun -n 2 would start it
    proc = subprocess.run([sys.executable, "-m", "dolfinx_friction", "sweep",
                           str(workdir / "swept.toml"), "--set", "contact.0.mu=0.1"],
                          capture_output=True, text=True, env=env, timeout=60)
    assert_one_line_error(Outcome([], proc.returncode, proc.stdout, proc.stderr),
                          ["sweep", "without mpirun"])


def test_split_values():
    from dolfinx_friction.cli.sweep import split_values
    assert split_values("0.1, 0.2,0.3") == ["0.1", "0.2", "0.3"]
    assert split_values("[0,0,-1],[0, 0, -2]") == ["[0,0,-1]", "[0, 0, -2]"]
    assert split_values('"a,b",\'c,d\',{x = [1,2]}') == ['"a,b"', "'c,d'", "{x = [1,2]}"]
    assert split_values(r'"a\",b",c') == [r'"a\",b"', "c"]


def test_worker_pool_killed_on_bad_input_ended_otherwise():
    """The workers start with the pool (importing while the sweep validates): a block that
    raises before any point ran kills them (a bad point is answered at once), and so are
    workers that were given no point (those that ran points end at the end of their input:
    every sweep test)."""
    from dolfinx_friction.cli.sweep import WorkerPool
    for bad in (True, False):
        with contextlib.suppress(ValueError), WorkerPool(2) as pool:
            procs = [w.proc for w in pool.idle]
            assert all(p.returncode is None for p in procs)
            if bad:
                raise ValueError("a bad point")
        assert [p.returncode for p in procs] == [-signal.SIGKILL] * 2


def test_jobs_default_to_the_cores():
    from dolfinx_friction.cli.sweep import default_jobs
    assert default_jobs() == len(os.sched_getaffinity(0))


# ------------------------------------------------------------------------------ plot
def test_plot_run_and_sweep(workdir, sweep):
    _, d = sweep
    out = cli("plot", d)
    assert out.status == 0 and out.stderr == "", str(out)
    assert_png(d / "sweep.png")
    point = d / "step.1.max_iterations=30,contact.0.mu=0.3"
    out = cli("plot", point, "-o", workdir / "charts" / "history.png")
    assert out.status == 0 and out.stderr == "", str(out)
    assert_png(workdir / "charts" / "history.png")
    out = cli("plot", point)
    assert out.status == 0, str(out)
    assert_png(point / "history.png")


@pytest.mark.parametrize("command", ["plot", "render"])
def test_not_a_results_folder_one_line(workdir, command):
    assert_one_line_error(cli(command, workdir), [str(workdir), "not a results folder"])
    assert_one_line_error(cli(command, workdir / "nowhere"), ["nowhere", "no such folder"])


# ------------------------------------------------------------------------------ render
@pytest.fixture(scope="module")
def can_render(workdir) -> None:
    """Skip unless VTK's XDMF reader is there and an off-screen picture can be drawn."""
    probe = ("from dolfinx_friction import viz\nimport pyvista, sys\n"
             "from vtkmodules.vtkIOXdmf2 import vtkXdmfReader\n"
             "p = pyvista.Plotter(off_screen=True)\np.add_mesh(pyvista.Sphere())\n"
             "p.screenshot(sys.argv[1])\n")
    path = workdir / "probe.png"
    proc = subprocess.run([sys.executable, "-c", probe, str(path)], capture_output=True,
                          text=True, env=cli_env(), timeout=120)
    if proc.returncode != 0 or not path.is_file():
        pytest.skip(f"no off-screen rendering here: {(proc.stderr.strip() or '?')[-200:]}")


@pytest.fixture(scope="module")
def fields_run(workdir) -> Path:
    d = workdir / "fields_out"
    out = cli("run", workdir / "fields.toml", "--out", d, "--quiet")
    assert out.status == 0, str(out)
    return d


@pytest.fixture(scope="module")
def last_picture(can_render, fields_run) -> Path:
    """``render`` of the serial run's last increment, default file name."""
    out = cli("render", fields_run)
    assert out.status == 0 and out.stderr == "", str(out)
    return fields_run / "render_step1_increment0003.png"  # the last of 4 increments


def test_render_last_and_chosen_increment(last_picture, fields_run, workdir):
    last = last_picture
    assert_png(last)
    first = workdir / "pictures" / "first.png"
    out = cli("render", fields_run, "--increment", "1", "--scalar", "status", "-o", first)
    assert out.status == 0 and out.stderr == "", str(out)
    assert_png(first)
    assert first.read_bytes() != last.read_bytes()
    out = cli("render", fields_run, "--increment", "-4", "--von-mises", "-o",
              workdir / "pictures" / "von_mises.png")
    assert out.status == 0, str(out)
    assert_png(workdir / "pictures" / "von_mises.png")


@pytest.mark.parametrize("args, expect", [
    (["--increment", "5"], ["--increment 5", "out of range", "4 converged"]),
    (["--increment", "0"], ["--increment 0", "out of range"]),
    (["-o", "picture.jpg"], ["picture.jpg", "PNG"]),
    (["--warp", "0"], ["--warp", "positive"]),
])
def test_render_bad_input_one_line(can_render, fields_run, args, expect):
    assert_one_line_error(cli("render", fields_run, *args), expect)


def test_render_without_fields_one_line(workdir, sweep):
    _, d = sweep
    point = d / "step.1.max_iterations=30,contact.0.mu=0.3"
    assert_one_line_error(cli("render", point), ["no field files", "output.fields"])


@pytest.mark.skipif(shutil.which("mpirun") is None, reason="mpirun not found")
def test_render_run_on_two_ranks(last_picture, workdir):
    d = workdir / "fields_mpi"
    out = mpirun_cli(2, "run", workdir / "fields.toml", "--out", d, "--quiet")
    assert out.status == 0, str(out)
    assert json.loads((d / "summary.json").read_text())["mpi_ranks"] == 2
    out = cli("render", d)
    assert out.status == 0 and out.stderr == "", str(out)
    picture = d / "render_step1_increment0003.png"
    assert_png(picture)
    import matplotlib.image  # the serial run's picture: the same
    a = matplotlib.image.imread(picture)
    b = matplotlib.image.imread(last_picture)
    assert a.shape == b.shape
    assert (np.abs(a - b).max(axis=2) > 0.05).mean() < 1e-3


def test_killed_run_draws_what_is_there(can_render, fields_run, workdir):
    """history.csv without summary.json: the picture and the chart of what converged,
    one line saying the run is incomplete, exit 2."""
    d = workdir / "killed"
    shutil.copytree(fields_run, d)
    (d / "summary.json").unlink()
    for png in d.glob("*.png"):
        png.unlink()
    lines = (d / "history.csv").read_text().splitlines(keepends=True)
    (d / "history.csv").write_text("".join(lines[:3]))  # header + 2 increments
    line = assert_one_line_error(cli("render", d), ["incomplete", "increment 2 of 2"])
    assert str(d) in line
    assert_png(d / "render_step1_increment0001.png")
    assert_one_line_error(cli("plot", d), ["incomplete", "2 converged increments"])
    assert_png(d / "history.png")


def test_sweep_interrupted_keeps_a_whole_table(workdir):
    """Ctrl-C (SIGINT to the process group, as a terminal sends it) after the first point:
    exit 130, one line, sweep.csv whole with the points that ended (interrupted ones too).
    The points after the first take 400 increments, so that some are still running when
    the signal comes (with 50, warm workers on Debian sid had ended all six by then)."""
    import os
    import signal
    import time
    d = workdir / "interrupted"
    proc = subprocess.Popen([sys.executable, "-m", "dolfinx_friction", "sweep",
                             str(workdir / "swept.toml"), "--set", "contact.0.mu=0.1,0.2,0.3",
                             "--set", "step.1.increments=3,400", "-j", "2", "--out", str(d),
                             "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=cli_env(), start_new_session=True)
    deadline = time.monotonic() + 120
    while not (d / "sweep.csv").exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=120)
    out = Outcome(proc.args, proc.returncode, stdout, stderr)
    assert_one_line_error(out, ["sweep interrupted", "of 6 points ended", "sweep.csv"], 130)
    header, rows = read_csv(d / "sweep.csv")
    assert 1 <= len(rows) < 6 and rows[0]["converged"] == "true"
    assert [int(r["point"]) for r in rows] == sorted(int(r["point"]) for r in rows)
    for row in rows[1:]:
        assert row["converged"] == "true" or "interrupted" in row["reason"]
    assert not [p for p in d.iterdir() if p.name.startswith(".")]
