"""Where a small run's CPU goes, from the interpreter to the last file: the floor of a
single ``run``, before and after a change.

    python benchmarks/bench_startup.py                       # this tree, RESULTS.md section
    python benchmarks/bench_startup.py --before 2b5918c      # and another commit beside it
    python benchmarks/bench_startup.py --repeats 3 --no-results

The scene is ``bench_small.py``'s ``boxes`` (801 dofs, 1 + 10 increments, all outputs).
Each package tree (this one; with ``--before``, the commit exported by ``git archive``
into ``$BENCH_WORK/trees``) is measured in fresh processes, one thread each, the
minimum CPU time (user + system, ``RUSAGE_CHILDREN``) over the repeats:

* ``interpreter``: ``python -c pass``;
* imports, cumulatively in the order a run loads them, each row the CPU it adds:
  numpy, mpi4py (``MPI_Init``, with the command line's singleton settings,
  ``cli.mpi.SINGLETON``), petsc4py, dolfinx (with ufl, basix, ffcx), scipy (sparse, k-d
  tree), numba, the package's own modules (with the contact kernels);
* in one process after those imports: numba's start (its typing and target contexts,
  which the first kernel call would set up), then the scene run twice through
  ``scene.run`` (all outputs written): the second run's CPU per phase
  (``summary.timers.cpu``), and ``first-call costs`` = first run minus second run
  (numba's cached kernels loaded, compiled forms looked up in dolfinx's JIT cache, modules
  a run imports on first use);
* ``whole command``: ``python -m dolfinx_friction run boxes.toml --quiet``; ``rest`` is
  what the rows above do not account for (argument parsing, reading and checking the
  scene before the imports, the interpreter's and MPI's exit).
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys

import _bench as B  # noqa: I001

import bench_small as S

from dolfinx_friction.cli.mpi import SINGLETON

#: (row, statement added to the ones before)
IMPORTS = [
    ("numpy", "import numpy"),
    ("mpi4py (MPI_Init)", "from mpi4py import MPI"),
    ("petsc4py", "from petsc4py import PETSc"),
    ("dolfinx, ufl, basix, ffcx", "import dolfinx, dolfinx.fem.petsc, dolfinx.io, ufl"),
    ("scipy (sparse, k-d tree)", "import scipy.sparse, scipy.spatial"),
    ("numba", "import numba"),
    ("dolfinx_friction (with its kernels)",
     "import dolfinx_friction.cli.frontend, dolfinx_friction.scene.runner; "
     "from dolfinx_friction.contact import backend; backend.compiled()"),
]
PHASES = ("setup", "contact_search", "contact_assembly", "bulk_assembly", "linear_solve",
          "output")
#: the child that runs the scene twice after the imports: CPU per phase of both runs
TWICE = """
import json, sys, time
from dolfinx_friction.scene.runner import run
from numba.core.registry import cpu_target
cpu = time.process_time()
cpu_target.typing_context.refresh()
cpu_target.target_context.refresh()
out = [time.process_time() - cpu]
for k in range(2):
    cpu = time.process_time()
    result = run(sys.argv[1], sys.argv[2] + str(k))
    out.append({"run": time.process_time() - cpu, **result.summary.timers.cpu})
print(json.dumps(out))
"""


def cpu_of(cmd: list[str], env: dict, cwd, repeats: int) -> float:
    """The least CPU time of ``cmd`` over ``repeats`` runs."""
    best = float("inf")
    for _ in range(repeats):
        c0 = B.children_cpu()
        subprocess.run(cmd, env=env, cwd=cwd, check=True, capture_output=True)
        best = min(best, B.children_cpu() - c0)
    return best


def measure(root: str, toml, repeats: int) -> dict[str, float]:
    """CPU seconds per row for the package tree at ``root``."""
    py, d = B.PYTHON, toml.parent
    env = dict(os.environ, PYTHONPATH=root, OMP_NUM_THREADS="1",
               **SINGLETON,
               DOLFINX_FRICTION_CACHE=str(B.work_dir("small") / "mesh_cache"))
    rows = {"interpreter": cpu_of([py, "-c", "pass"], env, d, repeats)}
    before, statements = rows["interpreter"], []
    for name, statement in IMPORTS:
        statements.append(statement)
        total = cpu_of([py, "-c", "; ".join(statements)], env, d, repeats)
        rows[name], before = max(total - before, 0.0), max(total, before)
    runs = []
    for k in range(repeats + 1):  # (the first: numba's cache filled for a new tree)
        for k in range(2):  # (an earlier run's files would be removed: not the first run's)
            shutil.rmtree(d / f"startup_out{k}", ignore_errors=True)
        proc = subprocess.run([py, "-c", TWICE, toml.name, "startup_out"], env=env, cwd=d,
                              check=True, capture_output=True, text=True)
        if k:
            runs.append(json.loads(proc.stdout.splitlines()[-1]))
    rows["numba start (typing, target contexts)"] = min(r[0] for r in runs)
    first, second = (min((r[k] for r in runs), key=lambda r: r["run"]) for k in (1, 2))
    rows["first-call costs (numba kernels, JIT lookups)"] = first["run"] - second["run"]
    for phase in PHASES:
        rows[f"run: {phase}"] = second[phase]
    rows["run: the rest of run()"] = second["run"] - sum(second[p] for p in PHASES)
    rows["whole command"] = cpu_of([py, "-m", "dolfinx_friction", "run", toml.name, "--quiet",
                                    "--out", "startup_cli"], env, d, repeats)
    rows["rest"] = rows["whole command"] - sum(
        v for k, v in rows.items() if k != "whole command")
    floor = ["interpreter", *(name for name, _ in IMPORTS), "numba start (typing, target contexts)"]
    rows["sum: the floor (interpreter, imports, numba start)"] = sum(rows[k] for k in floor)
    rows["sum: the run (first-call costs and run: rows)"] = sum(
        v for k, v in rows.items() if k.startswith(("run:", "first-call")))
    return rows


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", metavar="COMMIT", help="measure this commit too")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-results", action="store_true")
    args = ap.parse_args(argv)
    toml = S.prepare("boxes")
    machine = B.machine()
    trees = ([(args.before, str(B.export(args.before)))] if args.before else []) + \
        [(machine["commit"] or "this tree", str(B.ROOT))]
    columns = {name: measure(root, toml, args.repeats) for name, root in trees}
    load1 = B.load_average()
    names = list(columns)
    table = [[row] + [f"{columns[n][row]:.3f}" for n in names] for row in columns[names[-1]]]
    text = (f"`benchmarks/bench_startup.py`: {B.machine_line(machine, load1)}.\n\n"
            "Where the CPU of one `run` of bench_small's `boxes` (801 dofs, 1 + 10 increments, "
            "all outputs) goes, least over "
            f"{args.repeats} fresh processes per row, seconds (imports: what each adds to "
            "the ones above it; `run:` rows: a second run in the same process, the first "
            "run's extra in `first-call costs`):\n\n"
            + B.table(["CPU [s]"] + [f"at {n}" for n in names], table))
    print(text)
    if not args.no_results:
        B.write_section("Single runs: where a small run's CPU goes", text)


if __name__ == "__main__":
    sys.exit(main())
