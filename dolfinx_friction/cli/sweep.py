"""``dolfinx-friction sweep``: one scene run at every point of a cartesian product of
``--set`` values, each point in its own results folder, all summed up in ``sweep.csv``.

``--set KEY=V1,V2,...`` gives the values of one key; several ``--set`` span the cartesian
product (the first key varies slowest).  Values are separated by the commas that stand
outside brackets, braces and quotes, so ``u=[0,0,-1],[0,0,-2]`` is two vectors and
``name="a,b"`` one string; each value is read as ``run --set`` reads it (TOML, else a bare
string).

The points are listed (:func:`expand`), the warm worker processes started
(:class:`WorkerPool`: one per job, each importing the package, dolfinx and the contact
kernels at once, while this process validates every point with the scene reader,
:func:`validate`), then every point is run as ``run SCENE --out DIR/<point> --quiet --set
...`` in a worker (:mod:`~dolfinx_friction.cli.worker`: in-process, point after point,
with the exit status and stderr a fresh process would give), up to ``jobs`` at a time; the
first point runs alone until it has written its first increment, so that dolfinx compiles
the forms once for all (its JIT cache), not in several processes at once.
``DIR/sweep.csv`` is rewritten (atomically) each time a point ends: one row per ended
point, failed points too, with the last line its run printed on stderr.
"""
from __future__ import annotations

import csv
import io
import itertools
import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional, Sequence

import dolfinx_friction
from dolfinx_friction.io.files import write_atomic
from dolfinx_friction.io.reader import ResultsError, read_run
from dolfinx_friction.scene.toml import load_scene
from dolfinx_friction.scene.validation import check_mesh_file

__all__ = ["SweepError", "Point", "PointResult", "WorkerPool", "split_values", "expand",
           "validate", "run_sweep", "default_jobs", "SWEEP_CSV", "default_sweep_dir"]

SWEEP_CSV = "sweep.csv"
#: Columns of sweep.csv before the swept keys, and between the keys and the forces.
LEADING = ["point", "folder"]
RUN_COLUMNS = ["converged", "exit_status", "increments", "cutbacks", "newton_iterations",
               "wall_s", "t"]
_QUOTES = "\"'"
_OPEN, _CLOSE = "[{", "]}"
#: Characters kept in a point's folder name (others become "_").
_UNSAFE = re.compile(r"[^A-Za-z0-9._+=,\[\]-]")


class SweepError(ValueError):
    """Bad sweep input (one line naming the option or key)."""


def split_values(text: str) -> list[str]:
    """The values of ``V1,V2,...``: split at commas outside brackets, braces and quotes.

    Raises :class:`SweepError` for unbalanced brackets or an unterminated string.
    """
    values, start, depth, quote, k = [], 0, 0, "", 0
    while k < len(text):
        ch = text[k]
        if quote:
            if ch == "\\" and quote == '"':
                k += 1  # an escaped character of a basic string
            elif ch == quote:
                quote = ""
        elif ch in _QUOTES:
            quote = ch
        elif ch in _OPEN:
            depth += 1
        elif ch in _CLOSE:
            depth -= 1
            if depth < 0:
                raise SweepError(f"{text}: '{ch}' without its opening bracket")
        elif ch == "," and depth == 0:
            values.append(text[start:k].strip())
            start = k + 1
        k += 1
    if quote:
        raise SweepError(f"{text}: unterminated string")
    if depth:
        raise SweepError(f"{text}: unclosed bracket")
    values.append(text[start:].strip())
    return values


def _axis(option: str) -> tuple[str, list[str]]:
    """``(key, values)`` of one ``--set KEY=V1,V2,...``."""
    key, sep, text = option.partition("=")
    key = key.strip()
    if not sep or not key:
        raise SweepError(f"--set {option}: expected KEY=V1,V2,...")
    if not text.strip():
        raise SweepError(f"--set {option}: no values for {key}")
    try:
        values = split_values(text)
    except SweepError as exc:
        raise SweepError(f"--set {key}={exc}") from None
    if not all(values):
        raise SweepError(f"--set {option}: an empty value in the list of {key}")
    twice = next((v for k, v in enumerate(values) if v in values[:k]), None)
    if twice is not None:
        raise SweepError(f"--set {option}: {key} = {twice} is listed twice")
    return key, values


@dataclass(frozen=True)
class Point:
    """One point of a sweep: its number (from 1), the value of every key (as given) and
    the name of its results folder."""

    index: int
    values: tuple[tuple[str, str], ...]
    folder: str

    @property
    def overrides(self) -> list[str]:
        """The ``--set`` arguments of the point's run."""
        return _assignments(self.values)

    @property
    def label(self) -> str:
        """``key=value,key=value``."""
        return ",".join(self.overrides)


def _assignments(values: Sequence[tuple[str, str]]) -> list[str]:
    return [f"{key}={value}" for key, value in values]


def _folder_names(labels: list[str]) -> list[str]:
    """Folder names that say what the points hold: ``key=value,key=value`` with unsafe
    characters replaced by ``_``; numbered ``<n>_...`` when that makes two of them equal."""
    names = [_UNSAFE.sub("_", label)[:200] for label in labels]
    if len(set(names)) < len(names):
        names = [f"{k:03d}_{name}" for k, name in enumerate(names, 1)]
    return names


def expand(options: Sequence[str]) -> list[Point]:
    """The points of a sweep from its ``--set KEY=V1,V2,...`` options, not yet validated.
    Raises :class:`SweepError` (one line naming the option)."""
    if not options:
        raise SweepError("sweep: give at least one --set KEY=V1,V2,...")
    axes = [_axis(option) for option in options]
    keys = [key for key, _ in axes]
    twice = next((k for n, k in enumerate(keys) if k in keys[:n]), None)
    if twice is not None:
        raise SweepError(f"--set {twice}: the key is given twice")
    combos = [tuple(zip(keys, values)) for values in itertools.product(*(v for _, v in axes))]
    labels = [",".join(_assignments(combo)) for combo in combos]
    return [Point(n, combo, name) for n, (combo, name)
            in enumerate(zip(combos, _folder_names(labels)), 1)]


def validate(scene: Path, points: Sequence[Point]) -> None:
    """Every point read by the scene reader (and each mesh file checked) before anything
    runs.  Raises ``SceneError`` (one line naming the key)."""
    checked: set[Path] = set()
    for point in points:
        loaded = load_scene(scene, point.overrides)
        if Path(loaded.mesh) not in checked:
            checked.add(Path(loaded.mesh))
            check_mesh_file(loaded, scene)


def default_jobs() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # (not Linux)
        return os.cpu_count() or 1


def default_sweep_dir(scene: Path) -> Path:
    """``<scene stem>_sweep`` next to the scene file."""
    return scene.parent / f"{scene.stem}_sweep"


# ------------------------------------------------------------------------ running
@dataclass
class PointResult:
    """How one point ended: the exit status of its run (negative: killed by that
    signal), the last line it printed on stderr when it failed, its wall time [s]."""

    point: Point
    status: int
    reason: str
    wall: float


def _argv(scene: Path, point: Point, directory: Path) -> list[str]:
    """The ``run`` command line of a point."""
    sets = [arg for override in point.overrides for arg in ("--set", override)]
    return ["run", str(scene), "--out", str(directory / point.folder), "--quiet", *sets]


def _environment() -> dict[str, str]:
    """The runs import this very package (its folder first on PYTHONPATH)."""
    env = dict(os.environ)
    root = str(Path(dolfinx_friction.__file__).resolve().parents[1])
    env["PYTHONPATH"] = os.pathsep.join([root, *filter(None, env.get("PYTHONPATH", "")
                                                        .split(os.pathsep))])
    return env


_INTERRUPTED = {-signal.SIGINT, -signal.SIGTERM, 128 + signal.SIGINT, 128 + signal.SIGTERM}
"""Exit statuses of a run stopped by Ctrl-C or ``terminate()``."""


class _Worker:
    """A warm process running points one after another (:mod:`~dolfinx_friction.cli.worker`):
    the imports and the compiled forms are paid once per worker, not once per point.  It
    starts importing as soon as it is made."""

    def __init__(self, env: dict[str, str]):
        self.proc = subprocess.Popen([sys.executable, "-m", "dolfinx_friction.cli.worker"],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.DEVNULL, text=True, env=env)
        self.used = False  # whether it was given a point

    def run(self, argv: list[str]) -> tuple[int, str]:
        """One point's exit status and stderr; a worker that died gives its own status
        (negative: the signal that killed it)."""
        self.used = True
        try:
            self.proc.stdin.write(json.dumps(argv) + "\n")
            self.proc.stdin.flush()
            line = self.proc.stdout.readline()
        except OSError:
            line = ""
        if not line:
            return self.proc.wait(), ""
        reply = json.loads(line)
        return int(reply["status"]), str(reply["stderr"])

    @property
    def alive(self) -> bool:
        return self.proc.poll() is None

    def end(self) -> None:
        """Tell the worker to end (the end of its input); :meth:`wait` for it."""
        try:
            self.proc.stdin.close()
        except OSError:
            pass

    def wait(self, timeout: float) -> None:
        """Wait for the end of the worker (killed if it has not ended within ``timeout``)."""
        try:
            self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


class WorkerPool:
    """``size`` warm workers, started at once (they import while the caller goes on), that
    run the points of one sweep and can all be stopped (the running points terminated, no
    more started).  A context manager: on leaving, every worker ends; one that was given
    no point is killed (it has nothing to finish), all are when the block raised before
    any point ran (a bad point: the sweep answers at once)."""

    def __init__(self, size: int):
        self.size, self.env = size, _environment()
        self.stopped, self.started = False, False
        self.idle = [_Worker(self.env) for _ in range(size)]
        self.busy: set[_Worker] = set()
        self.lock = threading.Lock()

    def __enter__(self) -> "WorkerPool":
        return self

    def __exit__(self, kind, exc, tb) -> None:
        self.close(kill=exc is not None and not self.started)

    def run(self, scene: Path, directory: Path, point: Point) -> Optional[PointResult]:
        """Run one point on an idle worker (a new one should one have died); None when the
        pool was stopped before it began."""
        start = time.perf_counter()
        with self.lock:
            if self.stopped:
                return None
            self.started = True
            worker = self.idle.pop() if self.idle else _Worker(self.env)
            self.busy.add(worker)
        status, stderr = worker.run(_argv(scene, point, directory))
        with self.lock:
            self.busy.discard(worker)
            if self.stopped or not worker.alive:
                worker.end()
                worker.wait(10.0)
            else:
                self.idle.append(worker)
        lines = [line.strip() for line in stderr.splitlines() if line.strip()]
        reason = ""
        if status != 0:
            reason = lines[-1] if lines else f"killed by signal {-status}" \
                if status < 0 else f"exit status {status}"
            if self.stopped:  # (the run may have been killed before it could say so)
                reason = f"stopped with the interrupted sweep ({reason})"
            elif not lines and status in _INTERRUPTED:  # (before the sweep knew)
                reason = f"interrupted ({reason})"
        return PointResult(point, status, reason, time.perf_counter() - start)

    def stop(self) -> None:
        """Terminate the running points (each stops after its current increment, 143)."""
        with self.lock:
            self.stopped = True
            for worker in self.busy:
                worker.proc.terminate()

    def close(self, kill: bool = False) -> None:
        """End every worker, all at once (kill them, or those given no point); wait for
        them."""
        with self.lock:
            workers, self.idle = self.idle + list(self.busy), []
        for worker in workers:
            worker.proc.kill() if kill or not worker.used else worker.end()
        for worker in workers:
            worker.wait(10.0)


def run_sweep(scene: Path, points: Sequence[Point], directory: Path, pool: WorkerPool,
              on_result: Callable[[PointResult, dict], None] = lambda result, row: None
              ) -> list[PointResult]:
    """Run every point on the pool's workers, as many at a time as it has (the first one
    alone until its first increment is written: its forms are compiled), rewriting
    ``directory/sweep.csv`` as each ends and calling ``on_result(result, row)`` (its
    sweep.csv row); returns the results in point order.

    On an exception in the waiting thread (KeyboardInterrupt, or the signal handler's
    exception) the running points are terminated and waited for, sweep.csv lists every
    point that ended, and the exception goes on.
    """
    directory.mkdir(parents=True, exist_ok=True)
    keys = [key for key, _ in points[0].values] if points else []
    rows: dict[int, dict[str, str]] = {}
    results: dict[int, PointResult] = {}

    def ended(result: Optional[PointResult]) -> None:
        if result is None or result.point.index in results:
            return
        results[result.point.index] = result
        rows[result.point.index] = _row(result, directory)
        write_table(directory / SWEEP_CSV, keys, [rows[k] for k in sorted(rows)])
        on_result(result, rows[result.point.index])

    def run(point: Point) -> Optional[PointResult]:
        return pool.run(scene, directory, point)

    futures: list[Future] = []
    with ThreadPoolExecutor(max_workers=pool.size) as threads:
        try:
            first = directory / points[0].folder / "history.csv"
            since = time.time_ns()
            futures.append(threads.submit(run, points[0]))
            _wait_all(futures, ended, lambda: _has_increment(first, since))
            futures += [threads.submit(run, point) for point in points[1:]]
            _wait_all(futures, ended)
        except BaseException:
            pool.stop()
            threads.shutdown(wait=True, cancel_futures=True)
            for future in futures:  # the points stopped now are rows too
                if future.done() and not future.cancelled() and future.exception() is None:
                    ended(future.result())
            raise
    return [results[k] for k in sorted(results)]


def _wait_all(futures: list[Future], ended: Callable,
              until: Callable[[], bool] = lambda: False) -> None:
    """Wait for the futures, handing each result to ``ended`` as it comes (in short waits:
    the main thread stays responsive to Ctrl-C), or until ``until()`` (polled)."""
    pending = {future for future in futures if not future.done()}
    for future in futures:
        if future.done():
            ended(future.result())
    while pending and not until():
        done, pending = wait(pending, timeout=0.05, return_when=FIRST_COMPLETED)
        for future in sorted(done, key=futures.index):
            ended(future.result())


def _has_increment(history: Path, since: int) -> bool:
    """Whether a point's ``history.csv``, written since ``since`` (``time_ns``), has a row:
    its run set up (forms compiled) and converged its first increment."""
    try:
        return history.stat().st_mtime_ns >= since and history.read_bytes().count(b"\n") > 1
    except OSError:
        return False


# ------------------------------------------------------------------------ sweep.csv
def _row(result: PointResult, directory: Path) -> dict[str, str]:
    """The sweep.csv row of one point: from its summary.json and the last row of its
    history.csv (values copied as written), as far as they exist; ``wall_s`` is the wall
    time of the point's process (start-up included)."""
    point = result.point
    row = {"point": str(point.index), "folder": point.folder, **dict(point.values),
           "exit_status": str(result.status), "wall_s": f"{result.wall:.3f}",
           "reason": result.reason}
    try:
        run = read_run(directory / point.folder)
    except ResultsError:
        run = None
    summary = (run.summary if run else None) or {}
    converged = result.status == 0 and bool(summary.get("converged"))
    row["converged"] = "true" if converged else "false"
    if run is not None:
        row["increments"] = str(summary.get("increments", len(run.history)))
        row["cutbacks"] = str(summary.get("cutbacks", ""))
        row["newton_iterations"] = str(summary.get(
            "newton_iterations", sum(int(r["newton_iterations"]) for r in run.history)))
        if run.history:
            last = run.history[-1]
            row["t"] = last["t"]
            row.update({c: last[c] for c in run.force_columns()})
    return row


def write_table(path: Path, keys: Sequence[str], rows: Sequence[dict[str, str]]) -> None:
    """(Re)write sweep.csv atomically, one row per point that ended.

    Columns: ``point,folder``, the swept keys, ``converged,exit_status,increments,
    cutbacks,newton_iterations,wall_s,t``, the final ``R_*`` (and ``U_*``, ``F_*``)
    columns of the points' history.csv (in order of first appearance), ``reason``.
    """
    fixed = set(LEADING) | set(keys) | set(RUN_COLUMNS) | {"reason"}
    forces = list(dict.fromkeys(c for row in rows for c in row if c not in fixed))
    header = LEADING + list(keys) + RUN_COLUMNS + forces + ["reason"]
    text = io.StringIO()
    writer = csv.DictWriter(text, header, restval="", lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    write_atomic(path, text.getvalue())
