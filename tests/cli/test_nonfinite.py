"""No wrong answer reported as a result: a converged increment whose reactions,
displacements or contact values are not finite is a failed increment (cut back), never
written; so is an increment whose Jacobian is singular (a body that only the contact
held, pulled off it).

In process (serially and under ``mpirun -n 2``): the scene of ``test_cli`` (a block
pressed and slid on a foundation) is run through :func:`dolfinx_friction.run` while
Newton's result is poisoned with a NaN, on rank 0 only (the decision must be collective),
in a constrained row (a reaction: the residual norm leaves those rows out, so Newton
"converges") or in the contact state.
"""
from __future__ import annotations

import csv
import math
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from dolfinx_friction.nls import newton as newton_module
from dolfinx_friction.scene.runner import run
from dolfinx_friction.scene.toml import load_scene
from dolfinx_friction.scene.driver import ConvergenceError
from dolfinx_friction.reference import meshes
from tests.cli.test_cli import GOOD, RIGID, edited, toml_dumps

COMM = MPI.COMM_WORLD


@pytest.fixture(scope="module")
def mesh_dir() -> Path:
    """A directory made on rank 0 and known to every rank, with the mesh."""
    d = Path(COMM.bcast(tempfile.mkdtemp(prefix="dfx_nonfinite_") if COMM.rank == 0 else None))
    meshes.two_boxes(d / "two.msh", n_block=(2, 2, 1), n_foundation=(3, 3, 1))  # collective
    meshes.block_3d(d / "block.msh", n=(2, 2, 1))
    yield d
    COMM.barrier()
    if COMM.rank == 0:
        shutil.rmtree(d, ignore_errors=True)


def _scene(d: Path, name: str, edits=(), base=GOOD):
    path = d / f"{name}.toml"
    if COMM.rank == 0:
        path.write_text(toml_dumps(edited(base, list(edits))))
    COMM.barrier()
    return load_scene(path)


def _first_rank_with(n: int) -> int:
    """The lowest rank where ``n > 0`` (collective)."""
    return COMM.allreduce(COMM.rank if n > 0 else COMM.size, op=MPI.MIN)


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture
def poison(monkeypatch):
    """``poison(which, solves)``: after the Newton solves numbered in ``solves`` (1, 2, ...,
    counted over the run) put a NaN into ``which`` ("reaction": the internal force of a
    constrained row; "contact": the first slave pressure) on one rank only, the first
    that has such a value."""
    def install(which: str, solves) -> list[int]:
        count = [0]
        original = newton_module.Newton.solve

        def solve(self, problem, **kwargs):
            trace = original(self, problem, **kwargs)
            count[0] += 1
            if count[0] not in solves:
                return trace
            if which == "reaction":
                rows = problem.constrained_rows
                if COMM.rank == _first_rank_with(len(rows)):
                    problem.internal = problem.internal.copy()
                    problem.internal[rows[0]] = np.nan
            else:
                c = problem.contacts[0]
                real = c.state
                if COMM.rank == _first_rank_with(len(real().pressure)):
                    def state():
                        st = real()
                        st.pressure[:1] = np.nan
                        del c.state  # once: the instance attribute hides the method
                        return st
                    c.state = state
            return trace
        monkeypatch.setattr(newton_module.Newton, "solve", solve)
        return count
    return install


@pytest.mark.parametrize("which", ["reaction", "contact"])
def test_non_finite_converged_increment_is_cut_back(mesh_dir, poison, which):
    """Once: the increment is retried at half size (one cutback); every value written is
    finite, and the run ends as the unpoisoned one at t = 2."""
    poison(which, {2})  # the first attempt of the slide's first increment
    out = mesh_dir / f"cut_back_{which}"
    result = run(_scene(mesh_dir, f"cut_back_{which}"), out=out)
    assert result.summary.converged and result.summary.cutbacks == 1
    if COMM.rank == 0:
        rows = _rows(out / "history.csv")
        assert float(rows[-1]["t"]) == pytest.approx(2.0)
        for row in rows:
            assert all(math.isfinite(float(v)) for v in row.values()), row
        for row in _rows(out / "contact.csv"):
            values = [v for k, v in row.items() if k != "status"]
            assert all(math.isfinite(float(v)) for v in values), row


def test_non_finite_every_time_fails_and_writes_nothing(mesh_dir, poison):
    """Always non-finite from the slide on: the step fails after its cutbacks with the
    reason, and only the press is in the results."""
    poison("reaction", set(range(2, 1000)))
    out = mesh_dir / "never_finite"
    with pytest.raises(ConvergenceError, match="non-finite"):
        run(_scene(mesh_dir, "never_finite", [("step.1.max_cutbacks", 1)]), out=out)
    if COMM.rank == 0:
        rows = _rows(out / "history.csv")
        assert [(r["step"], r["increment"]) for r in rows] == [("0", "1")]
        assert {(r["step"], r["increment"]) for r in _rows(out / "contact.csv")} == {("0", "1")}


def test_singular_jacobian_fails_with_its_reason(mesh_dir):
    """A block that only a rigid floor holds (frictional contact), pressed, then its top let
    go and pulled up: once the contact opens nothing holds the block and the Jacobian is
    singular.  The pull fails after its cutbacks naming the singular Jacobian; only the
    press is written (it used to be accepted with the block 1e13 away, exit 0)."""
    pull = {"name": "pull", "increments": 1, "max_cutbacks": 2,
            "bc": [{"on": "top", "u": ["free", "free", "free"]}],
            "load": [{"on": "top", "traction": [0.0, 0.0, 10.0]}]}
    out = mesh_dir / "pulled_off"
    scene = _scene(mesh_dir, "pulled_off", [("step.1", pull)], base=RIGID)
    with pytest.raises(ConvergenceError, match="singular Jacobian") as info:
        run(scene, out=out)
    assert "\n" not in str(info.value)
    if COMM.rank == 0:
        rows = _rows(out / "history.csv")
        assert [(r["step"], r["increment"]) for r in rows] == [("0", "1"), ("0", "2")]
