"""Results of a run: history.csv, contact.csv, summary.json and XDMF fields.

Tables are written by rank 0.  Every converged increment is appended in one
``write`` before the next increment starts; field files of an increment are written
into a scratch folder (``fields/.<name>.partial``) that is renamed into place when
complete.  A run killed at any moment therefore leaves the increments already converged
complete and readable (the kernel keeps what a killed process wrote).  The tables and
time series are flushed to disk (``fsync``) once, when the solve ends, before
``summary.json`` (itself synced): an ``fsync`` per increment cost up to 5 ms each, four
per increment, on a disk shared with other jobs.

What a killed run leaves, precisely.  For each increment the files are written
in this order: the rows of ``contact.csv``, the field folder
``fields/step<s>_increment<iiii>``, each body's time series ``fields/<body>.xdmf``
(rewritten atomically, listing the folders in place), then the row of
``history.csv``.  So

* ``history.csv`` lists complete increments only; it is the record of what
  converged *and was fully written*;
* ``contact.csv`` holds the same increments, possibly followed by all the rows
  of the next one (the kill came before its ``history.csv`` row);
* ``fields/`` holds a complete folder for each increment of ``history.csv``,
  possibly one more (the same next increment), and at most one hidden
  ``.<name>.partial`` scratch folder, which is never a result;
* each time series ``fields/<body>.xdmf`` lists the increments of ``history.csv``,
  possibly followed by that next one (its folder in place), and only complete folders;
  a hidden ``.<body>.<token>.partial.xdmf`` may be left and is not a result;
* every line of the tables ends with a newline: an increment's rows go out in a
  single ``write(2)`` of whole lines (a reader may still treat a last line
  without its newline as incomplete, should the kernel ever cut such a write
  short);
* ``summary.json`` is written (atomically) only when the solve ends: all steps
  converged, or an increment diverged after all its cutbacks.

A write that fails (a full disk) is reported as one :class:`OutputError` naming the
file, raised on every rank, and leaves the tables as they were before the increment:
a table is cut back to its former length, this increment's ``contact.csv`` rows are
removed when a later part of it fails, and its scratch folder is deleted.  Field folders
are not started when the free space is below twice the last one's size: under MPI,
dolfinx aborts the process when HDF5 fails to close a file on a full disk.

On one rank the field files are written in memory first (a folder of the writer's own in
:data:`MEMORY`, emptied every increment, removed at the end or by a later run when a
signal that runs no Python code killed this one) and copied into the scratch folder: dolfinx
rewrites an XDMF file after each function it adds, and on a disk (ext4) a file rewritten
from its start is flushed when it is closed, eight times per body and increment
(benchmarks/RESULTS.md, "Studies: a 10-point sweep against ccx").  The files are the same.
"""
from __future__ import annotations

import errno
import json
import logging
import os
import shutil
import tempfile
import time
import weakref
from pathlib import Path
from typing import Optional

import numpy as np
import ufl

from dolfinx_friction import _compat as compat

from dolfinx_friction.io import xdmf_series as time_series
from dolfinx_friction.io.xdmf_fields import output_spaces, write_fields
from dolfinx_friction.contact.element import STATUS_NAMES
from dolfinx_friction.errors import OutputError
from dolfinx_friction.fem.contact_fields import SLAVE_COLUMNS, slave_rows
from dolfinx_friction.scene.build import ContactProblem
from dolfinx_friction.io.files import sync, write_atomic
from dolfinx_friction.scene.provenance import file_sha256
from dolfinx_friction.scene.driver import Increment, RunSummary

log = logging.getLogger(__name__)
OUR_FILES = ("history.csv", "contact.csv", "summary.json")
AXES = "xyz"


def _fault(path: Path, exc: BaseException) -> str:
    """The one line for a file that could not be written (a full disk said as such)."""
    if getattr(exc, "strerror", None):
        return f"{path}: cannot be written: {exc.strerror}"
    reason = " ".join(str(exc).split()).rstrip(".")
    try:  # HDF5 says only "failed to write": tell a full disk as such
        folder = next(p for p in (path, *path.parents) if p.exists())
        st = os.statvfs(folder)
        if st.f_bavail * st.f_frsize < 1 << 20:
            reason = (f"{os.strerror(errno.ENOSPC)} ({reason}; "
                      f"{st.f_bavail * st.f_frsize} bytes free)")
    except (OSError, StopIteration):
        pass
    return f"{path}: cannot be written: {reason}"


def _append(path: Path, text: str) -> None:
    """Append whole lines with one ``write`` (continued should it be short).  A write that
    fails (a full disk) is undone: the file is cut back to its former length, so that no
    partial line is left (truncating frees space, it needs none)."""
    data = memoryview(text.encode())
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        size = os.fstat(fd).st_size
        try:
            while data:
                data = data[os.write(fd, data):]
        except OSError:
            os.ftruncate(fd, size)
            raise
    finally:
        os.close(fd)


def _truncate(path: Path, size: int) -> None:
    with open(path, "rb+") as f:
        f.truncate(size)
        os.fsync(f.fileno())


def _collective(comm, error: Optional[str], reduce: bool = False) -> None:
    """Raise :class:`OutputError` on every rank when one rank (rank 0, or any rank when
    ``reduce``) failed to write: the others must not go on to the next collective."""
    errors = comm.allgather(error) if reduce else [comm.bcast(error, root=0)]
    error = next((e for e in errors if e), None)
    if error:
        raise OutputError(error)


#: a memory file system where a serial run writes its field files before they are copied to
#: the results (none: they are written in place)
MEMORY = Path("/dev/shm")
#: the name of a writer's folder in :data:`MEMORY`: this prefix, the process id, ``_``
MEMORY_PREFIX = "dolfinx_friction_fields_"
#: a folder of a process that is gone is removed once it is this old (seconds): a process
#: of another pid namespace that shares the memory file system writes into its folder
#: at every increment
ORPHAN_AGE = 3600.0


def _memory_folder() -> Optional[Path]:
    """A new folder in :data:`MEMORY` named after this process (the folders of processes
    killed before they could remove theirs removed), or None where there is none."""
    if not (MEMORY.is_dir() and os.access(MEMORY, os.W_OK)):
        return None
    _remove_orphans()
    try:
        return Path(tempfile.mkdtemp(prefix=f"{MEMORY_PREFIX}{os.getpid()}_", dir=MEMORY))
    except OSError:
        return None


def _remove_orphans() -> None:
    """Remove the folders in :data:`MEMORY` of processes that are gone, untouched for
    :data:`ORPHAN_AGE` (a process killed by a signal it cannot catch leaves its folder)."""
    now = time.time()
    for folder in MEMORY.glob(f"{MEMORY_PREFIX}*_*"):
        pid = folder.name[len(MEMORY_PREFIX):].split("_", 1)[0]
        try:
            if (pid.isdigit() and not _alive(int(pid))
                    and now - folder.stat().st_mtime > ORPHAN_AGE):
                shutil.rmtree(folder, ignore_errors=True)
        except OSError:
            pass  # removed meanwhile, or not ours to look at


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists (another user's counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass  # another user's
    return True


def _silence_hdf5() -> None:
    """Turn off HDF5's automatic error-stack printing (dozens of HDF5-DIAG lines on
    stderr for one failed write, e.g. on a full disk): the failure still raises in
    dolfinx, and is reported in one line.  The library is the one dolfinx loaded."""
    try:
        import ctypes
        with open("/proc/self/maps") as maps:
            paths = {line.split()[-1] for line in maps if "/libhdf5" in line}
        for path in paths:
            if os.path.basename(path).startswith(("libhdf5.so", "libhdf5_openmpi.so",
                                                  "libhdf5_mpich.so", "libhdf5_serial.so")):
                lib = ctypes.CDLL(path)
                lib.H5Eset_auto2.argtypes = [ctypes.c_int64, ctypes.c_void_p, ctypes.c_void_p]
                lib.H5Eset_auto2(0, None, None)  # H5E_DEFAULT
    except (OSError, AttributeError):
        pass  # no /proc, or another HDF5 build: its messages stay


def _fmt(values) -> str:
    return ",".join(f"{v:.17g}" if isinstance(v, float) else str(v) for v in values)


class ResultWriter:
    """Writes the outputs of one run of a :class:`ContactProblem` into ``directory``."""

    def __init__(self, problem: ContactProblem, reaction_groups: list[str], directory: Path,
                 fields: bool = True, contact_table: bool = True):
        self.problem, self.comm = problem, problem.comm
        self.dir = Path(directory)
        self.fields, self.contact_table = fields, contact_table
        self.rank0 = self.comm.rank == 0
        d = problem.gdim
        self._prepare_directory()
        self.history_header = ["step", "increment", "t", "newton_iterations", "residual",
                               "active", "slipping", "wall_s"]
        for g in reaction_groups:
            self.history_header += [f"R_{g}_{a}" for a in AXES[:d]]
        for r in problem.scene.rigids:
            self.history_header += [f"U_{r.name}_{a}" for a in AXES[:d]]
            self.history_header += [f"F_{r.name}_{a}" for a in AXES[:d]]
            self.history_header += [f"M_{r.name}_{a}" for a in (AXES[2:3] if d == 2 else AXES)]
        self.reaction_groups = reaction_groups
        ids = {name: self._canonical_ids(pair.state().X) for name, pair in problem.pairs.items()}
        offsets = np.cumsum([0] + [self.comm.allreduce(len(i)) for i in ids.values()])
        self._node_ids = {name: i + off for (name, i), off in zip(ids.items(), offsets)}
        error = None
        if self.rank0:
            path = self.dir / "history.csv"
            try:
                _append(path, ",".join(self.history_header) + "\n")
                if contact_table:
                    path = self.dir / "contact.csv"
                    cols = (["step", "increment", "node"] + list(AXES[:d]) +
                            ["gap", "pressure", "normal_force"] +
                            [f"tangential_force_{a}" for a in AXES[:d]] + ["slip", "status"])
                    _append(path, ",".join(cols) + "\n")
            except OSError as exc:
                error = _fault(path, exc)
        _collective(self.comm, error)
        if fields:
            self._field_writer = FieldWriter(problem, self.dir / "fields")

    def _prepare_directory(self) -> None:
        """Create the directory; results of an earlier run in it are replaced, and said so."""
        error = None
        if self.rank0:
            try:
                self.dir.mkdir(parents=True, exist_ok=True)
                old = [self.dir / f for f in OUR_FILES if (self.dir / f).exists()]
                if (self.dir / "fields").exists():
                    old.append(self.dir / "fields")
                if old:
                    log.info("overwriting the results of an earlier run in %s", self.dir)
                for path in old:
                    shutil.rmtree(path) if path.is_dir() else path.unlink()
                probe = self.dir / ".write_test"
                probe.write_text("")
                probe.unlink()
            except OSError as exc:
                error = f"output directory {self.dir}: {exc.strerror or exc}"
        error = self.comm.bcast(error, root=0)
        if error:
            raise OutputError(error)

    def _canonical_ids(self, X_local: np.ndarray) -> np.ndarray:
        """Slave node numbers that do not depend on the partition: order of reference
        coordinates, rounded to 1e-9 of the surface's extent (the coordinates of a node may
        differ in the last bits between partitions: they are tabulated from different cells)."""
        X = self.comm.gather(X_local, root=0)
        ids = None
        if self.rank0:
            allX = np.concatenate(X)
            unit = 1e-9 * max(float(np.ptp(allX, axis=0).max(initial=0.0)), 1e-300)
            order = np.lexsort(np.round(allX / unit).T[::-1])
            ranks = np.empty(len(allX), dtype=np.int64)
            ranks[order] = np.arange(len(allX))
            bounds = np.cumsum([0] + [len(x) for x in X])
            ids = [ranks[bounds[k]:bounds[k + 1]] for k in range(len(X))]
        return self.comm.scatter(ids, root=0)

    # ------------------------------------------------------------ per increment
    def increment(self, inc: Increment) -> None:
        """Write one converged increment: all of it, or (a write failed: a full disk)
        nothing; then :class:`OutputError` names the file, on every rank."""
        contact = self.dir / "contact.csv"
        size = contact.stat().st_size if self.rank0 and self.contact_table else 0
        try:
            if self.contact_table:
                self._contact_rows(inc)
            if self.fields:
                self._field_writer.write(inc)
            self._history_row(inc)
        except OutputError:
            if self.rank0 and self.contact_table:  # the rows of this increment go too
                try:
                    _truncate(contact, size)
                except OSError:
                    pass
            raise

    def _history_row(self, inc: Increment) -> None:
        d, error = self.problem.gdim, None
        if self.rank0:
            row = [inc.step, inc.increment, float(inc.t), inc.iterations, float(inc.residual),
                   inc.active, inc.slipping, float(inc.wall)]
            for g in self.reaction_groups:
                row += [float(v) for v in inc.reactions[g][:d]]
            for r in self.problem.scene.rigids:
                row += [float(v) for v in inc.rigid_u[r.name]]
                row += [float(v) for v in inc.rigid_f[r.name]]
                row += [float(v) for v in inc.rigid_m[r.name]]
            try:
                _append(self.dir / "history.csv", _fmt(row) + "\n")
            except OSError as exc:
                error = _fault(self.dir / "history.csv", exc)
        _collective(self.comm, error)

    def _contact_rows(self, inc: Increment) -> None:
        blocks = []
        for name, pair in self.problem.pairs.items():
            st = pair.state()
            rows = slave_rows(st)
            blocks.append(np.column_stack([self._node_ids[name][st.has_element],
                                           *(rows[c] for c in SLAVE_COLUMNS)]))
        width = 3 + 3 * self.problem.gdim + 3
        local = np.concatenate(blocks) if blocks else np.zeros((0, width))
        rows = self.comm.gather(local, root=0)
        error = None
        if self.rank0:
            try:
                self._append_contact(inc, np.concatenate(rows))
            except OSError as exc:
                error = _fault(self.dir / "contact.csv", exc)
        _collective(self.comm, error)

    def _append_contact(self, inc: Increment, table: np.ndarray) -> None:
        table = table[np.argsort(table[:, 0], kind="stable")]
        # (as _fmt writes them: "%.17g" is the format of f"{v:.17g}")
        line = f"{inc.step},{inc.increment},%d,{','.join(['%.17g'] * (table.shape[1] - 2))},%s\n"
        _append(self.dir / "contact.csv", "".join(
            line % (int(row[0]), *row[1:-1].tolist(), STATUS_NAMES[int(row[-1])])
            for row in table))

    # ---------------------------------------------------------------- summary
    def summary(self, run: RunSummary, extra: Optional[dict] = None) -> None:
        _collective(self.comm, self._write_summary(run, extra))

    def _write_summary(self, run: RunSummary, extra: Optional[dict]) -> Optional[str]:
        """summary.json (rank 0); why it could not be written, or None."""
        p = self.problem
        n_dofs = p.layout.n_global * p.gdim
        slaves = self.comm.allreduce(sum(len(pair.state().nodes) for pair in p.pairs.values()))
        if not self.rank0:
            return None
        scene = p.scene
        source = scene.source
        data = {
            "scene": str(source) if source else None,
            "scene_file_sha256": file_sha256(Path(source)) if source else None,
            "title": scene.title,
            "overrides": list(scene.overrides),
            "versions": compat.versions(),
            "mpi_ranks": self.comm.size,
            "dofs": n_dofs,
            "slave_nodes": slaves,
            "steps": [s.name for s in scene.steps],
            "increments": run.increments,
            "cutbacks": run.cutbacks,
            "newton_iterations": run.newton_iterations,
            "wall_time_s": run.wall,
            "wall_time_per_phase_s": run.timers.phases,
            "converged": run.converged,
            "failure": run.failure or None,
        }
        data.update(extra or {})
        written = [self.dir / "history.csv"] + ([self.dir / "contact.csv"] if
                                                self.contact_table else [])
        if self.fields:
            written += self._field_writer.series_files()
        try:
            for path in written:
                sync(path)
            path = self.dir / "summary.json"
            write_atomic(path, json.dumps(data, indent=2) + "\n")
        except OSError as exc:
            return _fault(path, exc)
        return None


class FieldWriter:
    """Displacement, contact and stress fields of every body: one XDMF file per body and
    increment, and per body the time series over them (:mod:`time_series`)."""

    def __init__(self, problem: ContactProblem, directory: Path):
        self.problem, self.dir = problem, directory
        error = None
        if problem.comm.rank == 0:
            try:
                directory.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                error = _fault(directory, exc)
        _collective(problem.comm, error)
        _silence_hdf5()
        self._size = 0  # bytes of the last increment's field folder and time series
        self._series: dict[str, list[str]] = {f.body.name: [] for f in problem.fields}
        # compiled once (and kept in the problem's workspace for later runs): a form
        # compiler cache hit still costs ~10 ms per expression
        self.outputs = [problem.shared(("output spaces", id(f.V)),
                                       lambda f=f: (f.V, output_spaces(f)))[1]
                        for f in problem.fields]
        self.stresses = [problem.shared(("stresses", id(f.u), f.body),
                                        lambda f=f: (f.u, self._stresses(f)))[1]
                         for f in problem.fields]
        self._functions: list[dict] = [{} for _ in problem.fields]  # output Functions by name
        # where the field files are written before they are copied into place (serial)
        self._memory = _memory_folder() if problem.comm.size == 1 else None
        if self._memory is not None:
            weakref.finalize(self, shutil.rmtree, str(self._memory), True)

    def _stresses(self, field) -> list:
        """Cell functions and the expressions that fill them: the Cauchy stress
        (gdim x gdim) and its von Mises stress."""
        from dolfinx_friction.scene.build import cauchy_stress, von_mises
        sigma, d, mesh = cauchy_stress(field), field.gdim, field.V.mesh
        in_plane = ufl.as_matrix([[sigma[i, j] for j in range(d)] for i in range(d)])
        return [compat.cell_function(in_plane, mesh, (d, d), "cauchy_stress"),
                compat.cell_function(von_mises(sigma), mesh, (), "von_mises")]

    def write(self, inc: Increment) -> None:
        comm = self.problem.comm
        name = f"step{inc.step}_increment{inc.increment:04d}"
        scratch = self.dir / f".{name}.partial"
        error = None
        if comm.rank == 0:
            shutil.rmtree(scratch, ignore_errors=True)
            error = self._space_for(self.dir / name)
            try:
                error or scratch.mkdir()
            except OSError as exc:
                error = _fault(self.dir / name, exc)
        _collective(comm, error)
        self.problem.system.scatter()
        for field, spaces, stresses, kept in zip(self.problem.fields, self.outputs,
                                                 self.stresses, self._functions):
            path = scratch / f"{field.body.name}.xdmf"
            for f, expression in stresses:
                f.interpolate(expression)
            try:  # HDF5 writes collectively: every rank sees the failure
                write_fields(path if self._memory is None else self._memory / path.name,
                             field, spaces, self.problem.contact_fields(field), inc.t,
                             [f for f, _ in stresses], kept)
                if self._memory is not None:
                    self._copy_out(scratch)
            except (RuntimeError, OSError) as exc:
                error = _fault(self.dir / name / path.name, exc)
            if comm.allreduce(error is not None):  # (any rank: the others must stop too)
                break
        try:
            _collective(comm, error, reduce=True)
        except OutputError:
            if comm.rank == 0:  # never a result; removing it gives the space back
                shutil.rmtree(scratch, ignore_errors=True)
            raise
        if comm.rank == 0:
            try:
                os.replace(scratch, self.dir / name)
            except OSError as exc:
                error = _fault(self.dir / name, exc)
            error = error or self._extend_series(self.dir / name, inc.t)
        _collective(comm, error)

    def _copy_out(self, folder: Path) -> None:
        """Move the files written in memory into ``folder`` (each a new file there)."""
        for source in self._memory.iterdir():
            shutil.copyfile(source, folder / source.name)
            source.unlink()

    def series_files(self) -> list[Path]:
        """The time series written so far."""
        return [self.dir / f"{name}.xdmf" for name, grids in self._series.items() if grids]

    def _extend_series(self, folder: Path, t: float) -> Optional[str]:
        """Add the increment in ``folder`` (in place) to every body's time series
        ``fields/<body>.xdmf``, each rewritten atomically (rank 0); why not, or None.  A
        failure removes the folder: the series never lacks an increment that is written."""
        grids = {}
        for field in self.problem.fields:
            name = field.body.name
            grids[name] = self._series[name] + [
                time_series.increment_grid(folder / f"{name}.xdmf", t)]
        written = []
        for name, series in grids.items():
            path = self.dir / f"{name}.xdmf"
            try:
                write_atomic(path, time_series.collection(name, series), durable=False)
            except OSError as exc:
                try:  # the series written already drop this increment, then its folder goes
                    for done in written:
                        write_atomic(self.dir / f"{done}.xdmf",
                                     time_series.collection(done, self._series[done]),
                                     durable=False)
                    shutil.rmtree(folder)
                except OSError:
                    pass  # the folder stays, complete, as a series written refers to it
                return _fault(path, exc)
            written.append(name)
        self._series = grids
        # what the next increment needs: its folder and the series rewritten beside the old
        self._size = sum(f.stat().st_size for f in folder.iterdir()) + sum(
            (self.dir / f"{name}.xdmf").stat().st_size for name in grids)
        return None

    def _space_for(self, folder: Path) -> Optional[str]:
        """Why the next field folder would not fit (or None): free space below twice the
        last folder's size.  Checked before writing, because HDF5 does not fail cleanly on
        a full disk: under MPI, dolfinx's XDMFFile then aborts the process as it closes."""
        try:
            st = os.statvfs(self.dir)
        except OSError:
            return None
        free = st.f_bavail * st.f_frsize
        if free >= 2 * self._size + (64 << 10):
            return None
        return (f"{folder}: cannot be written: {os.strerror(errno.ENOSPC)} ({free} bytes free; "
                f"the last increment's fields took {self._size})")
