"""A run killed with SIGKILL leaves the increments already written complete and readable;
one stopped by SIGINT / SIGTERM, or by a full disk, says so in one line.

The guarantee (documented in ``dolfinx_friction/io/writer.py``): per increment the
rows of ``contact.csv`` are written first, then the field folder, then the row
of ``history.csv``.  After a kill

* ``history.csv`` holds complete rows of consecutive converged increments;
* ``contact.csv`` holds complete lines, with complete blocks of rows for the
  increments of ``history.csv`` and possibly for the next one;
* every visible folder in ``fields/`` is complete (XDMF that parses, its HDF5
  file present); there is one for each increment of ``history.csv``, possibly
  one more (the same next one); a hidden ``.<name>.partial`` scratch folder may
  be left and is not a result;
* each body's time series ``fields/<body>.xdmf`` lists the increments of ``history.csv``,
  possibly that next one, and refers only to datasets of complete folders (also when the
  kill comes between a folder and its ``history.csv`` row, where the series are
  rewritten);
* ``summary.json`` is not written (the run did not end).

SIGINT / SIGTERM (serially and under ``mpirun -n 2``, where Open MPI turns either into
SIGTERM for the ranks and kills them a second later): exactly one line on stderr,
"interrupted at step k, increment n; the results of converged increments are in DIR",
naming the increment after the last one written, exit 130 / 143 (serial), the same
complete tables and no summary.  A full disk (a small tmpfs, mounted if we are root):
one line naming the file, exit 2, the tables cut back to whole increments that match
(no partial row, no increment's rows without its history row).

Serial only: the runs are subprocesses started from a serial pytest.
"""
from __future__ import annotations

import csv
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from mpi4py import MPI

from dolfinx_friction import _compat as compat
from dolfinx_friction.reference import meshes
from dolfinx_friction.io.writer import MEMORY, MEMORY_PREFIX, ORPHAN_AGE
from dolfinx_friction.reference.cases import block_on_foundation_toml
from tests.cli.test_outputs import series_grids

pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1,
                                reason="kills a subprocess started from a serial pytest")

ROOT = Path(__file__).resolve().parents[2]
BODIES = ("block", "foundation")
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
SCENE = block_on_foundation_toml("two.msh", title="many increments, killed on the way",
                                 slide_increments=40)


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


def _folders(fields: Path) -> int:
    try:
        return sum(1 for e in os.scandir(fields) if e.name.startswith("step"))
    except FileNotFoundError:
        return 0


def _time_to_kill(out: Path, moment: str) -> bool:
    """``any``: once history.csv holds 3 rows; ``fields``: in the window between an
    increment's field folder and its history.csv row (where the time series are
    rewritten), else after 30 rows."""
    rows = _data_rows(out / "history.csv")
    if moment == "any" or rows >= 30:
        return rows >= 3
    return rows >= 3 and _folders(out / "fields") > rows


@pytest.fixture(scope="module", params=["any", "fields"])
def killed_run(tmp_path_factory, request):
    d = tmp_path_factory.mktemp("kill")
    meshes.two_boxes(d / "two.msh", n_block=(2, 2, 1), n_foundation=(3, 3, 1))
    (d / "scene.toml").write_text(SCENE)
    out = d / "results"
    proc = subprocess.Popen([sys.executable, "-m", "dolfinx_friction", "run", str(d / "scene.toml"),
                             "--out", str(out), "--quiet"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=_env())
    deadline = time.monotonic() + 240
    try:
        while not _time_to_kill(out, request.param):
            assert proc.poll() is None, (f"the run ended before it was killed "
                                         f"(exit {proc.returncode}): {proc.stderr.read()!r}")
            assert time.monotonic() < deadline, "the run is too slow to reach 3 increments"
            time.sleep(0.01 if request.param == "any" else 0.0002)
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
    series = {f"{body}.xdmf" for body in BODIES}
    for entry in sorted(fields.iterdir()):
        if ".partial" in entry.name:  # a field folder's scratch, a series' partial file
            assert entry.name.startswith("."), f"scratch file {entry.name} is not hidden"
            continue
        if entry.name in series:
            continue
        match = re.fullmatch(r"step(\d+)_increment(\d{4})", entry.name)
        assert match and entry.is_dir(), f"unexpected entry {entry.name} in fields/"
        results.append((int(match.group(1)), int(match.group(2))))
        for body in BODIES:
            xdmf = entry / f"{body}.xdmf"
            root = ET.parse(xdmf).getroot()  # complete XML
            items = [i.text.strip() for i in root.iter("DataItem") if i.get("Format") == "HDF"]
            assert items, f"{xdmf}: no data"
            for item in items:
                h5 = entry / item.split(":", 1)[0]
                assert h5.read_bytes()[:8] == HDF5_SIGNATURE, f"{h5} missing or not HDF5"
    # fields are written before the history row: every recorded increment has its folder
    assert results in (done, done + [following]), (results, done)
    # each body's time series lists complete folders only: those of history.csv, possibly
    # the next one
    for body in BODIES:
        listed = [tuple(int(v) for v in re.fullmatch(r"step(\d+)_increment(\d{4})",
                                                     g.get("Name")).groups())
                  for g in series_grids(fields, body)]
        assert listed in (done, done + [following]) and set(listed) <= set(results), \
            (body, listed, done)


def test_no_summary_of_an_unfinished_run(killed_run):
    assert not (killed_run / "summary.json").exists()


# ------------------------------------------------------------------ SIGINT / SIGTERM

LINE = re.compile(r"dolfinx-friction: interrupted at step (\d+), increment (\d+); "
                  r"the results of converged increments are in (.+)")


def _command(ranks: int) -> tuple[list[str], dict[str, str]]:
    program = [sys.executable, "-m", "dolfinx_friction", "run"]
    if ranks == 1:
        return program, _env()
    return [*compat.mpirun_command(ranks), *program], compat.mpirun_environment(_env())


def _run_until(d: Path, ranks: int, rows: int, signum: int, *args: str):
    """Start a run, send ``signum`` once ``history.csv`` holds ``rows`` rows (to
    ``mpirun`` itself under MPI, as Ctrl-C in a terminal would); (status, stderr, out)."""
    out = d / "results"
    command, env = _command(ranks)
    proc = subprocess.Popen([*command, str(d / "scene.toml"), "--out", str(out), "--quiet",
                             *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            env=env, text=True)
    deadline = time.monotonic() + 240
    try:
        while _data_rows(out / "history.csv") < rows:
            assert proc.poll() is None, (f"the run ended before the signal "
                                         f"(exit {proc.returncode}): {proc.stderr.read()!r}")
            assert time.monotonic() < deadline, "the run is too slow"
            time.sleep(0.01)
        os.kill(proc.pid, signum)
        stderr = proc.stderr.read()
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=60)
        proc.stderr.close()
    return proc.returncode, compat.mpirun_stderr(stderr), out


def _increments(path: Path) -> list[tuple[int, int]]:
    _, rows = _read_table(path)
    seen: dict[tuple[int, int], None] = {}
    for r in rows:
        seen[(int(r[0]), int(r[1]))] = None
    return list(seen)


#: Under mpirun, in about 1 run of 5 (Open MPI 4.1.4, 2 oversubscribed cores) neither rank
#: prints anything: history.csv stops growing the moment mpirun gets the signal, and the
#: ranks die at its SIGKILL two seconds later without having run any Python code (not
#: understood yet; see the commit message).  Not strict: it passes most of the time.
MPI_FLAKY = pytest.mark.xfail(strict=False, reason="under mpirun the ranks sometimes stall "
                                                   "when mpirun gets the signal: no line")


@pytest.mark.parametrize("ranks", [1, pytest.param(2, marks=MPI_FLAKY)], ids=["serial", "2ranks"])
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_one_line(tmp_path, signum, ranks):
    if ranks > 1 and shutil.which("mpirun") is None:
        pytest.skip("mpirun not found")
    meshes.two_boxes(tmp_path / "two.msh", n_block=(2, 2, 1), n_foundation=(3, 3, 1))
    (tmp_path / "scene.toml").write_text(SCENE)
    status, stderr, out = _run_until(tmp_path, ranks, 3, signum)
    lines = stderr.splitlines()
    if ranks > 1:  # Open MPI 4's launcher, tearing the job down, now and then says this
        lines = [line for line in lines if not line.startswith("[warn] Epoll ")]
    assert len(lines) == 1 and "Traceback" not in stderr, stderr
    match = LINE.fullmatch(lines[0])
    assert match, lines[0]
    if ranks == 1:
        assert status == {signal.SIGINT: 130, signal.SIGTERM: 143}[signum], (status, stderr)
    else:  # mpirun's own status (Open MPI 4: 1 once it has forwarded a signal)
        assert status != 0, (status, stderr)
    assert match.group(3) == str(out)
    done = _increments(out / "history.csv")
    assert len(done) >= 3
    # the increment named is the one after the last written: the next of its step
    # (or the first of the next step)
    step, increment = int(match.group(1)), int(match.group(2))
    last = done[-1]
    named = [(last[0], last[1] + 1), (last[0] + 1, 1)]
    if ranks > 1:  # the increment after one that mpirun's SIGKILL cut short as it was written
        named.append((last[0], last[1] + 2))
    assert (step, increment) in named, (lines[0], done)
    listed = _increments(out / "contact.csv")
    fields = sorted((int(m.group(1)), int(m.group(2))) for m in
                    (re.fullmatch(r"step(\d+)_increment(\d{4})", e.name)
                     for e in (out / "fields").iterdir()) if m)
    if ranks == 1:  # stopped between increments: tables and fields list the same ones
        assert listed == done and fields == done, (listed, fields, done)
    else:  # mpirun kills the ranks a second after its SIGTERM: at most the next one more
        following = [(last[0], last[1] + 1)]
        assert listed in (done, done + following) and fields in (done, done + following)
    assert not (out / "summary.json").exists()


# ------------------------------------------------------------------ a full disk

def _can_mount() -> bool:
    return os.geteuid() == 0 and shutil.which("mount") is not None


@pytest.fixture
def small_disk(tmp_path):
    """A tmpfs of a given size at tmp_path / "disk" (root only)."""
    mounted = []

    def mount(size: str) -> Path:
        where = tmp_path / "disk"
        where.mkdir()
        proc = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs",
                               str(where)], capture_output=True, text=True)
        if proc.returncode != 0:
            pytest.skip(f"cannot mount a tmpfs: {proc.stderr.strip()}")
        mounted.append(where)
        return where
    yield mount
    for where in mounted:
        subprocess.run(["umount", str(where)], check=False)


@pytest.mark.skipif(not _can_mount(), reason="mounting a small tmpfs needs root")
@pytest.mark.parametrize("ranks", [1, 2], ids=["serial", "2ranks"])
@pytest.mark.parametrize("what", ["tables", "fields"])
def test_full_disk_one_line(tmp_path, small_disk, what, ranks):
    """The disk fills up while the tables (no fields: 12 KiB) or the fields (120 KiB) are
    written: one line naming the file, exit 2, whole increments only, tables that agree."""
    if ranks > 1 and shutil.which("mpirun") is None:
        pytest.skip("mpirun not found")
    meshes.two_boxes(tmp_path / "two.msh", n_block=(2, 2, 1), n_foundation=(3, 3, 1))
    (tmp_path / "scene.toml").write_text(SCENE)
    disk = small_disk("12k" if what == "tables" else "120k")
    out = disk / "results"
    command, env = _command(ranks)
    proc = subprocess.run([*command, str(tmp_path / "scene.toml"), "--out", str(out),
                           "--quiet", "--set", f"output.fields={str(what == 'fields').lower()}"],
                          capture_output=True, text=True, env=env, timeout=300)
    stderr = compat.mpirun_stderr(proc.stderr)
    lines = stderr.splitlines()
    assert len(lines) == 1 and "Traceback" not in stderr, stderr
    assert proc.returncode == 2, (proc.returncode, stderr)
    assert "No space left on device" in lines[0], lines[0]
    if what == "tables":
        assert f"{out}/contact.csv" in lines[0] or f"{out}/history.csv" in lines[0], lines[0]
    else:
        assert f"{out}/fields/step" in lines[0], lines[0]
    done = _increments(out / "history.csv")  # whole rows only (_read_table checks)
    assert done, "nothing was written before the disk was full"
    assert _increments(out / "contact.csv") == done
    header, rows = _read_table(out / "contact.csv")
    assert len(rows) == 9 * len(done)  # every increment's block whole: 9 slave nodes
    if what == "fields":
        visible = sorted(e.name for e in (out / "fields").iterdir() if e.is_dir()
                         and not e.name.startswith("."))
        assert visible == [f"step{s}_increment{i:04d}" for s, i in done], visible
        for body in BODIES:
            assert [g.get("Name") for g in series_grids(out / "fields", body)] == visible
    assert not (out / "summary.json").exists()


# ------------------------------------------------------------------ SIGKILL
def test_a_killed_runs_memory_folder_goes_with_a_later_run(tmp_path):
    """SIGKILL (no Python code runs) leaves a serial run's folder in MEMORY behind, where
    its field files are staged; a later serial run that writes fields removes it once it is
    ORPHAN_AGE old (26 such folders had gathered from a day of test runs), and keeps the
    folder of a process that is alive."""
    if not (MEMORY.is_dir() and os.access(MEMORY, os.W_OK)):
        pytest.skip(f"no writable {MEMORY}")
    meshes.two_boxes(tmp_path / "two.msh", n_block=(2, 2, 1), n_foundation=(3, 3, 1))
    (tmp_path / "scene.toml").write_text(SCENE)
    before = set(MEMORY.glob(f"{MEMORY_PREFIX}*"))
    status, _, _ = _run_until(tmp_path, 1, 3, signal.SIGKILL)
    assert status == -signal.SIGKILL
    orphans = [f for f in set(MEMORY.glob(f"{MEMORY_PREFIX}*")) - before  # (other tests'
               if not Path("/proc", f.name[len(MEMORY_PREFIX):].split("_")[0]).exists()]  # live)
    assert len(orphans) == 1, orphans
    live = Path(tempfile.mkdtemp(prefix=f"{MEMORY_PREFIX}{os.getpid()}_", dir=MEMORY))
    try:
        old = time.time() - 2.0 * ORPHAN_AGE
        for folder in (*orphans, live):
            os.utime(folder, (old, old))
        command, env = _command(1)
        again = subprocess.run([*command, str(tmp_path / "scene.toml"), "--out",
                                str(tmp_path / "again"), "--quiet"], env=env,
                               capture_output=True, text=True, timeout=240)
        assert again.returncode == 0, again.stderr
        assert not orphans[0].exists() and live.exists()
    finally:
        shutil.rmtree(live, ignore_errors=True)
