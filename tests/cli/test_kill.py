"""A run killed with SIGKILL leaves the increments already written complete and readable.

The guarantee (documented in ``dolfinx_friction/output.py``): per increment the
rows of ``contact.csv`` are written first, then the field folder, then the row
of ``history.csv``.  After a kill

* ``history.csv`` holds complete rows of consecutive converged increments;
* ``contact.csv`` holds complete lines, with complete blocks of rows for the
  increments of ``history.csv`` and possibly for the next one;
* every visible folder in ``fields/`` is complete (XDMF that parses, its HDF5
  file present); there is one for each increment of ``history.csv``, possibly
  one more (the same next one); a hidden ``.<name>.partial`` scratch folder may
  be left and is not a result;
* ``summary.json`` is not written (the run did not end).

Serial only: the run is a subprocess started from a serial pytest.
"""
from __future__ import annotations

import csv
import os
import re
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from mpi4py import MPI

from tests import meshes

pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1,
                                reason="kills a subprocess started from a serial pytest")

ROOT = Path(__file__).resolve().parents[2]
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
SCENE = """\
title = "many increments, killed on the way"
[mesh]
file = "two.msh"
[[body]]
name = "block"
E = 1000.0
nu = 0.3
[[body]]
name = "foundation"
E = 1000.0
nu = 0.3
[[contact]]
slave = "block_bottom"
master = "foundation_top"
mu = 0.3
[[step]]
name = "press"
  [[step.bc]]
  on = "foundation_bottom"
  u = [0.0, 0.0, 0.0]
  [[step.bc]]
  on = "block_top"
  u = [0.0, 0.0, -0.01]
[[step]]
name = "slide"
increments = 40
  [[step.bc]]
  on = "block_top"
  u = [0.2, 0.0, -0.01]
[output]
fields = true
"""


def _env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("OMPI_COMM_WORLD", "OMPI_MCA_ess", "PMIX_", "PMI_"))}
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in
                                        env.get("PYTHONPATH", "").split(os.pathsep) if p])
    return env


def _data_rows(path: Path) -> int:
    try:
        return max(0, path.read_bytes().count(b"\n") - 1)
    except FileNotFoundError:
        return 0


def _read_table(path: Path) -> tuple[list[str], list[list[str]]]:
    raw = path.read_bytes()
    assert raw.endswith(b"\n"), f"{path.name}: last line is partial: {raw[-200:]!r}"
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    for k, row in enumerate(body):
        assert len(row) == len(header), f"{path.name} row {k + 1} is incomplete: {row}"
    return header, body


@pytest.fixture(scope="module")
def killed_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("kill")
    meshes.two_boxes(d / "two.msh", n_block=(2, 2, 1), n_foundation=(3, 3, 1))
    (d / "scene.toml").write_text(SCENE)
    out = d / "results"
    proc = subprocess.Popen([sys.executable, "-m", "dolfinx_friction", "run", str(d / "scene.toml"),
                             "--out", str(out), "--quiet"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=_env())
    deadline = time.monotonic() + 240
    try:
        while _data_rows(out / "history.csv") < 3:
            assert proc.poll() is None, (f"the run ended before it was killed "
                                         f"(exit {proc.returncode}): {proc.stderr.read()!r}")
            assert time.monotonic() < deadline, "the run is too slow to reach 3 increments"
            time.sleep(0.01)
        assert proc.poll() is None, "the run ended before it was killed"
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait(timeout=60)
        proc.stderr.close()
    assert proc.returncode == -signal.SIGKILL
    return out


def test_history_has_complete_rows(killed_run):
    header, rows = _read_table(killed_run / "history.csv")
    assert header[:8] == ["step", "increment", "t", "newton_iterations", "residual", "active",
                          "slipping", "wall_s"]
    assert header[8:] == [f"R_{g}_{a}" for g in ("foundation_bottom", "block_top") for a in "xyz"]
    assert len(rows) >= 3
    increments = [(int(r[0]), int(r[1])) for r in rows]
    assert increments == [(0, 1)] + [(1, i) for i in range(1, len(rows))]
    for row in rows:
        assert all(float(v) == float(v) for v in row)  # every value parses, none is NaN


def test_contact_table_matches_history(killed_run):
    _, history = _read_table(killed_run / "history.csv")
    done = [(int(r[0]), int(r[1])) for r in history]
    header, rows = _read_table(killed_run / "contact.csv")
    assert header[-1] == "status" and len(header) == 14
    blocks: dict[tuple[int, int], list[list[str]]] = {}
    for row in rows:
        assert row[-1] in ("open", "stick", "slip"), row
        blocks.setdefault((int(row[0]), int(row[1])), []).append(row)
    listed = list(blocks)
    # contact.csv is written before history.csv: at most the next increment more
    following = (done[-1][0], done[-1][1] + 1)
    assert listed in (done, done + [following]), (listed, done)
    for key, block in blocks.items():  # every increment's block complete: all slave nodes
        assert sorted(int(r[2]) for r in block) == list(range(9)), key


def test_field_folders_are_complete(killed_run):
    _, history = _read_table(killed_run / "history.csv")
    done = [(int(r[0]), int(r[1])) for r in history]
    following = (done[-1][0], done[-1][1] + 1)
    fields = killed_run / "fields"
    results = []
    for entry in sorted(fields.iterdir()):
        if entry.name.endswith(".partial"):
            assert entry.name.startswith("."), f"scratch folder {entry.name} is not hidden"
            continue
        match = re.fullmatch(r"step(\d+)_increment(\d{4})", entry.name)
        assert match and entry.is_dir(), f"unexpected entry {entry.name} in fields/"
        results.append((int(match.group(1)), int(match.group(2))))
        for body in ("block", "foundation"):
            xdmf = entry / f"{body}.xdmf"
            root = ET.parse(xdmf).getroot()  # complete XML
            items = [i.text.strip() for i in root.iter("DataItem") if i.get("Format") == "HDF"]
            assert items, f"{xdmf}: no data"
            for item in items:
                h5 = entry / item.split(":", 1)[0]
                assert h5.read_bytes()[:8] == HDF5_SIGNATURE, f"{h5} missing or not HDF5"
    # fields are written before the history row: every recorded increment has its folder
    assert results in (done, done + [following]), (results, done)


def test_no_summary_of_an_unfinished_run(killed_run):
    assert not (killed_run / "summary.json").exists()
