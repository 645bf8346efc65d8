"""The Hertz verification matrix (issue #26 item 4): errors, CPU, Newton iterations.

Every cell of ``tests/verification/test_hertz_matrix.py``, serially and on 2 ranks.

    python benchmarks/bench_hertz_matrix.py                  # both, writes RESULTS.md
    python benchmarks/bench_hertz_matrix.py --no-results     # print only
    python benchmarks/bench_hertz_matrix.py --cells 2d-p1 --h 0.05,0.025   # other meshes

The cells: 2D and 3D Hertz (:mod:`dolfinx_friction.reference.hertz`), displacement degree
1 and 2 (geometric order = degree), ``method`` penalty and augmented, on the test's meshes
(``reference.hertz.MESH_SIZE``) unless ``--h`` names others.  Each run is timed after an untimed
warm-up of its form compilation; the 2-rank rows come from this script run under
``mpirun -n 2`` by itself (``--rows``).  CPU is the slowest rank's.  The table goes to
the subsection "Verification matrix (issue 26 item 4)" of "Hertz: speed vs accuracy".
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import _bench as B  # noqa: I001  (threads, sys.path)

SECTION, TITLE = "Hertz: speed vs accuracy", "Verification matrix (issue 26 item 4)"
CELLS = {"2d-p1": (2, 1), "2d-p2": (2, 2), "3d-p1": (3, 1), "3d-p2": (3, 2)}
METHODS = ("penalty", "augmented")


def measure(cells: list[str], hs: list[float] | None, out: Path) -> list[dict]:
    """Run every cell on this process's communicator; the rows (rank 0 writes ``out``)."""
    from mpi4py import MPI

    from dolfinx_friction.reference.hertz import MESH_SIZE, hertz_fit, hertz_mesh, hertz_scene
    comm = MPI.COMM_WORLD
    rows, warm = [], set()
    for cell in cells:
        dim, degree = CELLS[cell]
        for h in hs or [MESH_SIZE[dim, degree]]:
            mesh = B.work_dir("hertz_matrix") / f"hertz{dim}d_h{h}_order{degree}.msh"
            if not comm.bcast(mesh.exists()):
                hertz_mesh(mesh, dim, h, order=degree)
            for method in METHODS:
                if (dim, degree) not in warm:  # form compilation, untimed
                    B.timed_run(hertz_scene(mesh, dim, degree, method))
                    warm.add((dim, degree))
                result, num = B.timed_run(hertz_scene(mesh, dim, degree, method))
                fit = hertz_fit(result, dim)
                penetration = max(max(i.penetration.values()) for i in result.increments)
                rows.append({"cell": cell, "h": h, "method": method, "ranks": comm.size,
                             "dofs": num["dofs"], "newton": num["newton"],
                             "cutbacks": num["cutbacks"], "cpu": num["cpu"], "wall": num["wall"],
                             "load": num["load"], "a_over_h": fit.a / h,
                             "err_p0": fit.err_p0, "err_a": fit.err_a,
                             "penetration": penetration})
                del result
                if comm.rank == 0:
                    r = rows[-1]
                    print(f"{cell} h={h} {method:9s} ranks={comm.size} "
                          f"err_p0={100 * r['err_p0']:+.3f}% err_a={100 * r['err_a']:+.3f}% "
                          f"newton={r['newton']} cpu={r['cpu']:.2f}s wall={r['wall']:.2f}s",
                          flush=True)
                    out.write_text(json.dumps(rows, indent=1))
    return rows


def two_ranks(argv: list[str]) -> list[dict]:
    """This script's rows under ``mpirun -n 2``."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "rows.json"
        env = {**os.environ, **B.MPIRUN_ENV,
               "PYTHONPATH": os.pathsep.join([str(B.ROOT), os.environ.get("PYTHONPATH", "")])}
        subprocess.run(["mpirun", "-n", "2", "--oversubscribe", "--bind-to", "none",
                        B.PYTHON, __file__, "--rows", str(out), *argv], check=True, env=env)
        return json.loads(out.read_text())


def report(rows: list[dict], machine: dict, load_end: float) -> str:
    def pct(x: float) -> str:
        return f"{100 * x:+.3f}"
    table_rows = []
    for r in sorted(rows, key=lambda r: (r["cell"], r["h"], METHODS.index(r["method"]),
                                          r["ranks"])):
        table_rows.append([r["cell"].replace("-", " ").upper(),
                           r["h"], f"{r['a_over_h']:.1f}", r["method"], r["ranks"],
                           f"{r['dofs']:,}", pct(r["err_p0"]), pct(r["err_a"]),
                           f"{100 * r['penetration']:.2g}",
                           f"{r['newton']}" + (f" ({r['cutbacks']} cb)" if r["cutbacks"] else ""),
                           B.fmt_s(r["cpu"]), B.fmt_s(r["wall"])])
    serial = {(r["cell"], r["h"], r["method"]): r for r in rows if r["ranks"] == 1}
    diffs = [abs(r[k] - serial[r["cell"], r["h"], r["method"]][k]) for r in rows
             if r["ranks"] > 1 and (r["cell"], r["h"], r["method"]) in serial
             for k in ("err_p0", "err_a")]
    agree = (f"* serial and 2 ranks: the errors differ by at most {max(diffs):.1e} (relative "
             "to p0 and a)" if diffs else "* serial only")
    return "\n".join([
        f"### {TITLE}",
        "",
        "`benchmarks/bench_hertz_matrix.py`: the cells of "
        "`tests/verification/test_hertz_matrix.py` (its docstring says what the reference is "
        "and why): the scenes of `dolfinx_friction.reference.hertz` (R = 10, E = 1000, "
        "nu = 0.3, rigid plane, frictionless, one increment, contact settings at their "
        "defaults but `method`), geometric order = displacement degree; error = fitted "
        "p0 and a (elliptic fit of the nodal pressures, p > 0.2 max p) against half-space "
        "Hertz for the measured load; overclosure in % of the slave spacing; CPU = the "
        "slowest rank's CPU seconds of the whole `run()` after an untimed warm-up; the test "
        "asserts |error| < 0.5 % on each, 1 % on 3D P2 (the next subsection says why).",
        "",
        f"* {B.machine_line(machine, load_end)}",
        agree,
        "",
        B.table(["cell", "h", "a/h", "method", "ranks", "dofs", "err p0 [%]", "err a [%]",
                 "overclosure [%]", "Newton its", "CPU [s]", "wall [s]"], table_rows),
    ])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", default=",".join(CELLS))
    ap.add_argument("--h", help="comma-separated element sizes instead of the test's")
    ap.add_argument("--no-results", action="store_true", help="do not touch RESULTS.md")
    ap.add_argument("--serial-only", action="store_true")
    ap.add_argument("--rows", help=argparse.SUPPRESS)  # internal: rows of this run -> file
    args = ap.parse_args(argv)
    cells = args.cells.split(",")
    hs = [float(h) for h in args.h.split(",")] if args.h else None
    if args.rows:
        measure(cells, hs, Path(args.rows))
        return
    machine = B.machine()
    with tempfile.TemporaryDirectory() as tmp:
        rows = measure(cells, hs, Path(tmp) / "rows.json")
    if not args.serial_only:
        passed = ["--cells", args.cells] + (["--h", args.h] if args.h else [])
        rows += two_ranks(passed)
    text = report(rows, machine, B.load_average())
    print(text)
    if not args.no_results:
        B.write_subsection(SECTION, TITLE, text)


if __name__ == "__main__":
    sys.exit(main())
