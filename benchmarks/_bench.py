"""Plumbing shared by the benchmark scripts ``benchmarks/bench_*.py``.

* One thread per process (``OMP_NUM_THREADS`` etc. set before numpy/PETSc load),
  so that CPU time is compute time and CalculiX (run with 1 thread) is compared
  like for like; numpy without huge-page advice, as the command line starts it
  (:mod:`dolfinx_friction.cli.environment`): a run in a benchmark's process is timed
  as ``dolfinx-friction run`` would run it.
* :func:`timed_run` runs a scene in memory and returns the numbers the
  benchmarks tabulate.  Phase times come from the solver's own timers, which
  record this process's CPU time (:func:`time.process_time`) next to the wall
  clock: the benchmark machine is
  shared with other jobs, and time-sharing inflates wall times by an unknown,
  varying factor, so the tables show CPU seconds and list the wall seconds too.
* :func:`machine` describes the machine (nproc, CPU, RAM, date, load average),
  :func:`write_section` replaces one ``## `` section of ``benchmarks/RESULTS.md`` (its
  earlier subsections kept) and leaves every other section alone.
* :func:`demo_module` imports a demo script (``demos/<name>.py``) to reuse its
  ``build_mesh``.

Scratch files (meshes, CalculiX decks) go to ``$BENCH_WORK`` (default
``/tmp/dolfinx_friction_bench``), never into the repository.
"""
from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import contextlib  # noqa: E402
import datetime  # noqa: E402
import gc  # noqa: E402
import importlib.util  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import re  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import types  # noqa: E402
from pathlib import Path  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
BENCH = ROOT / "benchmarks"
FIGURES = BENCH / "figures"
RESULTS = BENCH / "RESULTS.md"
DEMOS = ROOT / "demos"
WORK = Path(os.environ.get("BENCH_WORK", "/tmp/dolfinx_friction_bench"))
# this checkout's package and demos, after the trees PYTHONPATH names (a before/after
# comparison runs these scripts on an exported commit's package: ``export``)
_GIVEN = {os.path.abspath(p) for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p}
_AT = 1 + max((i for i, p in enumerate(sys.path) if p and os.path.abspath(p) in _GIVEN),
              default=-1)
for _p in (str(DEMOS), str(ROOT)):
    if _p not in sys.path:
        sys.path.insert(_AT, _p)

from dolfinx_friction.cli import environment  # noqa: E402  (imports no numpy)

if not environment.prepare():  # pragma: no cover - a script that imported numpy first
    raise SystemExit("benchmarks/_bench.py must be imported before numpy (or start Python "
                     "with NUMPY_MADVISE_HUGEPAGE set)")

#: the interpreter that has pyvista (the demos import it) and dolfinx
PYTHON = sys.executable
#: Open MPI as root; ranks yield the core while they wait (the machine is oversubscribed by
#: other jobs: busy-waiting ranks would steal the core from the rank they wait for)
MPIRUN_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
              "OMPI_MCA_mpi_yield_when_idle": "1"}


def work_dir(name: str) -> Path:
    d = WORK / name
    d.mkdir(parents=True, exist_ok=True)
    return d


# ----------------------------------------------------------------------------- machine
def export(commit: str) -> Path:
    """The package as it was at ``commit``, exported (``git archive``) into the work
    directory: the root to put on ``PYTHONPATH`` for a before/after comparison."""
    root = work_dir("trees") / commit
    if not (root / "dolfinx_friction").is_dir():
        root.mkdir(exist_ok=True)
        archive = subprocess.run(["git", "archive", commit, "dolfinx_friction"], cwd=ROOT,
                                 check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(root)], input=archive, check=True)
    return root


def load_average() -> float:
    return os.getloadavg()[0]


def machine() -> dict:
    cpu = "unknown"
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    mem = 0.0
    with contextlib.suppress(OSError, ValueError, IndexError):
        mem = int(Path("/proc/meminfo").read_text().split()[1]) / 2 ** 20
    commit = ""
    with contextlib.suppress(OSError, subprocess.SubprocessError):
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                                capture_output=True, text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "dolfinx_friction"], cwd=ROOT,
                               capture_output=True, text=True, timeout=10).stdout.strip()
        if commit and dirty:
            commit += f" + uncommitted changes in {len(dirty.splitlines())} package file(s)"
    return {"nproc": os.cpu_count(), "cpu": cpu, "ram_gib": round(mem, 1), "commit": commit,
            "date": datetime.datetime.now().strftime("%Y-%m-%d %H:%M"),
            "load": [round(x, 2) for x in os.getloadavg()],
            "python": platform.python_version()}


def machine_line(m: dict, load_end: float | None = None) -> str:
    end = f" / {load_end:.1f} at the end" if load_end is not None else ""
    pkg = f"; package at commit {m['commit']}" if m.get("commit") else ""
    return (f"machine: {m['nproc']} cores (nproc), CPU `{m['cpu']}`, {m['ram_gib']:.0f} GiB RAM, "
            f"{m['date']}; 1-min load average {m['load'][0]:.1f} at the start{end} "
            f"(other jobs share the machine){pkg}")


def peak_rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


# ----------------------------------------------------------------------------- runs
def timed_run(scene, comm=None, max_increments: int | None = None, **kwargs):
    """Run ``scene`` in memory; return ``(RunResult, numbers)``.

    ``numbers``: dofs, wall and cpu seconds of the whole run, Newton iterations,
    cutbacks, iterations per increment, phase seconds (``phases``: CPU, ``phases_wall``:
    wall clock; the slowest rank's), load average, peak RSS.
    ``max_increments``: stop after that many converged increments.
    """
    from mpi4py import MPI

    from dolfinx_friction.scene.runner import run
    comm = comm or MPI.COMM_WORLD
    release_petsc_garbage(comm)
    load0 = load_average()
    comm.barrier()
    w0, c0 = time.perf_counter(), time.process_time()
    result = run(scene, write=False, comm=comm, max_increments=max_increments, **kwargs)
    _last_meshes[:] = [body.mesh for body in result.problem.meshes.bodies.values()]
    comm.barrier()
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    s = result.summary
    # phases are per rank; report the slowest rank (what the wall clock waits for)
    phases_wall = {k: comm.allreduce(float(v), op=MPI.MAX) for k, v in s.timers.phases.items()}
    phases = {k: comm.allreduce(float(v), op=MPI.MAX) for k, v in s.timers.cpu.items()}
    numbers = {
        "dofs": int(result.problem.u.getSize()),
        "ranks": comm.size,
        "wall": comm.allreduce(wall, op=MPI.MAX),
        "cpu": comm.allreduce(cpu, op=MPI.MAX),
        "newton": s.newton_iterations,
        "cutbacks": s.cutbacks,
        "increments": s.increments,
        "iterations": [inc.iterations for inc in result.increments],
        "phases": phases,
        "phases_wall": phases_wall,
        "cpu_per_rank": comm.allgather(cpu),
        "load": [load0, load_average()],
        "rss_mib": comm.allreduce(peak_rss_mib(), op=MPI.MAX),
        "linear_solves": s.linear_solves,
    }
    return result, numbers


#: the meshes of the last timed run (on every rank), whose communicators hold its PETSc
#: objects once its result is dropped
_last_meshes: list = []


def release_petsc_garbage(comm=None) -> None:
    """Destroy the PETSc objects of earlier runs (collective).

    A run frees its factorisations as it ends; the rest of it (Jacobians, vectors) is
    collected when its result is dropped, and petsc4py destroys collected objects only in
    ``PETSc.garbage_cleanup`` on their own communicator, its mesh's, which dies with the
    mesh.  So the last timed run's meshes are kept until this call cleans their
    communicators (without it: ~4 KiB per dof per run, measured 5.5 MiB a run at 1.4k dofs)
    before ``comm``'s.
    """
    from petsc4py import PETSc

    from dolfinx_friction.nls.linear import release_garbage
    gc.collect()
    release_garbage([m.comm for m in _last_meshes])
    _last_meshes.clear()
    PETSc.garbage_cleanup(comm)


def demo_module(name: str):
    """Import ``demos/<name>.py`` (None if it does not exist)."""
    path = DEMOS / f"{name}.py"
    if not path.exists():
        return None
    if "_common" not in sys.modules:
        try:  # the demos' helper imports pyvista (in .venv); without it a stub will do
            import _common  # noqa: F401
        except ImportError:
            stub = types.ModuleType("_common")
            stub.HERE = DEMOS
            sys.modules["_common"] = stub
    spec = importlib.util.spec_from_file_location(f"demo_{name}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def profile_call(fn, top: int = 14):
    """Run ``fn()`` under cProfile; return ``(its result, rows)``, rows = the ``top`` functions
    by own time: ``(own seconds, cumulative seconds, calls, "file:line(function)")``, plus
    the total profiled seconds as the last row ``(total, total, 0, "total")``."""
    import cProfile
    import pstats
    prof = cProfile.Profile()
    ret = prof.runcall(fn)
    stats = pstats.Stats(prof)
    rows = []
    for (file, line, func), (cc, nc, tt, ct, _) in stats.stats.items():
        short = "/".join(Path(file).parts[-2:]) if file != "~" else ""
        rows.append((tt, ct, nc, f"{short}:{line}({func})" if short else func))
    rows.sort(key=lambda r: -r[0])
    return ret, rows[:top] + [(stats.total_tt, stats.total_tt, 0, "total")]


def profile_table(rows, label: str = "") -> str:
    total = rows[-1][0]
    body = [[f"{100 * tt / total:.1f} %", f"{tt:.2f}", f"{ct:.2f}", nc, f"`{name}`"]
            for tt, ct, nc, name in rows[:-1]]
    return (f"{label}cProfile, top functions by own time (total {total:.1f} s profiled):\n\n"
            + table(["share", "own [s]", "cumulative [s]", "calls", "function"], body,
                    "rrrrl"))


# ----------------------------------------------------------------------------- workers
def worker_parser(doc: str) -> argparse.ArgumentParser:
    """Parser of a script run again as its own workers: hidden --worker, --quick, --no-results."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--worker", nargs="+", help=argparse.SUPPRESS)  # see run_worker
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--no-results", action="store_true")
    return ap


def run_worker(script: Path, args: list[str], ranks: int = 1, timeout: float = 3600.0,
               env: dict | None = None) -> dict:
    """Run ``script --worker ARGS`` (under ``mpirun -n ranks`` if ranks > 1) and return the
    JSON dict it prints on its last line starting with ``RESULT ``."""
    cmd = [PYTHON, str(script), "--worker", *args]
    if ranks > 1:
        cmd = ["mpirun", "-n", str(ranks), "--bind-to", "none", *cmd]
    full_env = dict(os.environ, **MPIRUN_ENV, **(env or {}))
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=full_env)
    for line in reversed(proc.stdout.splitlines()):
        if line.startswith("RESULT "):
            return json.loads(line[len("RESULT "):])
    tail = "\n".join((proc.stdout + proc.stderr).splitlines()[-25:])
    raise RuntimeError(f"worker {' '.join(cmd)} failed (exit {proc.returncode}):\n{tail}")


def rank_series(script: Path, args_per_rank: dict[int, list[str]], line, repeat: int = 1,
                save: str | None = None) -> dict[int, list[dict]]:
    """Run ``script``'s worker once per rank count with that count's arguments, ``repeat``
    rounds; the runs by rank count, each printed as ``line(ranks, run)`` and the whole
    series saved to ``save`` (JSON) as each run finishes."""
    runs: dict[int, list[dict]] = {}
    for _ in range(repeat):
        for ranks, args in args_per_rank.items():
            run = run_worker(script, args, ranks=ranks, timeout=6 * 3600)
            runs.setdefault(ranks, []).append(run)
            print(line(ranks, run), flush=True)
            if save:
                Path(save).write_text(json.dumps(runs, indent=1))
    return runs


def emit(result: dict) -> None:
    """Print a worker's result (rank 0 only)."""
    from mpi4py import MPI
    if MPI.COMM_WORLD.rank == 0:
        print("RESULT " + json.dumps(result), flush=True)


# ----------------------------------------------------------------------------- output
def _subsection(title: str) -> re.Pattern:
    return re.compile(rf"^### {re.escape(title)}\n.*?(?=^##+ |\Z)", re.S | re.M)


def write_section(title: str, body: str, keep: tuple[str, ...] | None = None) -> None:
    """Replace (or append) the section ``## title`` of RESULTS.md; other sections are kept,
    and so are its subsections ``### <keep>`` (default: every subsection ``body`` does not
    write anew: the earlier runs recorded under it, and what other scripts wrote there)."""
    text = RESULTS.read_text() if RESULTS.exists() else "# Benchmarks\n"
    block = f"## {title}\n\n{body.strip()}\n"
    pattern = re.compile(rf"^## {re.escape(title)}\n.*?(?=^## |\Z)", re.S | re.M)
    old = pattern.search(text)
    if keep is None:
        written = set(re.findall(r"^### (.+)$", body, re.M))
        keep = tuple(t for t in re.findall(r"^### (.+)$", old.group(0), re.M)
                     if t not in written) if old else ()
    for sub in keep:
        kept = _subsection(sub).search(old.group(0)) if old else None
        if kept:
            block += "\n" + kept.group(0).strip() + "\n"
    if old:
        text = pattern.sub(lambda _: block + "\n", text, count=1)
    else:
        text = text.rstrip("\n") + "\n\n" + block
    RESULTS.write_text(text.rstrip("\n") + "\n")


def write_subsection(section: str, title: str, body: str) -> None:
    """Replace the subsection ``### title`` (``body`` starts with that line) of the section
    ``## section`` of RESULTS.md, or add it at the section's end."""
    text = RESULTS.read_text()
    pattern = re.compile(rf"^## {re.escape(section)}\n.*?(?=^## |\Z)", re.S | re.M)
    old = pattern.search(text)
    if old is None:
        raise SystemExit(f"RESULTS.md has no section '## {section}'")
    part = old.group(0)
    block = body.strip() + "\n\n"
    if _subsection(title).search(part):
        part = _subsection(title).sub(lambda _: block, part, count=1)
    else:
        part = part.rstrip("\n") + "\n\n" + block
    text = text[:old.start()] + part + text[old.end():]
    RESULTS.write_text(text.rstrip("\n") + "\n")


def table(header: list[str], rows: list[list], align: str | None = None) -> str:
    align = align or "l" + "r" * (len(header) - 1)
    sep = ["---:" if a == "r" else "---" for a in align]
    lines = ["| " + " | ".join(header) + " |", "| " + " | ".join(sep) + " |"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    FIGURES.mkdir(parents=True, exist_ok=True)
    return plt


def save_figure(fig, name: str, title: str, machine: dict | None = None,
                fontsize: int = 10) -> Path:
    """Title ``fig`` (with the machine's load, cores and commit when given), save it as
    ``figures/name`` and close it; the path."""
    if machine is not None:
        title += (f" (load {machine['load'][0]:.1f} on {machine['nproc']} cores, "
                  f"commit {machine['commit']})")
    fig.suptitle(title, fontsize=fontsize)
    fig.tight_layout()
    path = FIGURES / name
    fig.savefig(path)
    import matplotlib.pyplot as plt
    plt.close(fig)
    return path


def pareto(points: list[tuple[float, float]]) -> list[int]:
    """Indices of the points (time, error) that no other point beats in both."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], float("inf")
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def fmt_s(x: float) -> str:
    return f"{x:.3g}" if x < 100 else f"{x:.0f}"
