"""The condensed solve (kept bulk factorisation, contact by Woodbury) on 1 and 2 MPI ranks.

    python benchmarks/bench_condensed.py                      # foundation 24 x 24 x 36 (~70k dofs)
    python benchmarks/bench_condensed.py --quick              # foundation 10 x 10 x 12 (< 1 min)
    python benchmarks/bench_condensed.py --ranks 2 --label "before" --json before.json --no-results
    python benchmarks/bench_condensed.py --load before.json --load after.json

Scene: a small block (6 x 6 x 3 hexahedra) pressed 1 increment and slid ``--slide``
increments (default 3) on a deep foundation (``--foundation``, default 24 x 24 x 36
hexahedra; ``reference.meshes.two_boxes``), E = 1000, nu = 0.3, mu = 0.3, K = 50 E, MUMPS
(``[solver] linear = "direct"``, the kept factorisation where it pays): the contact
surface is small against the bulk, where the condensed path pays.  bench_cost's
two_boxes at n = 8..12 is not such a scene: there the cost model refuses the path on 1 and
2 ranks (its ``G`` would need thousands of columns for 9 solves), and the runs are the
kept factorisation's (RESULTS.md, "The condensed path under MPI").

The script runs itself under ``mpirun -n 1`` and ``-n 2`` (``--bind-to none``).  To compare
with the path taken without condensing under MPI, run a copy of the script with an older
package (``--label``, ``--json``) and report both with ``--load``.  Reported: Newton and
Krylov iterations, condensed solves, the linear solve's and the whole run's wall and CPU
seconds (the slowest rank), the last reaction's relative difference from the first run.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import _bench as B  # noqa: I001

import bench_cost as C

BLOCK = (6, 6, 3)


def mesh(foundation: tuple[int, int, int]) -> Path:
    """The block on the deep foundation, built if missing."""
    from dolfinx_friction.reference.meshes import two_boxes
    path = B.work_dir("boxes") / ("deep_" + "x".join(map(str, foundation)) + ".msh")
    if not path.exists():
        two_boxes(path, BLOCK, foundation)
    return path


def worker(args: list[str]) -> None:
    from dataclasses import replace

    from mpi4py import MPI
    foundation, slide = tuple(int(x) for x in args[0].split("x")), int(args[1])
    scene = replace(C.scene(4, True, slide_increments=slide), mesh=mesh(foundation))
    result, num = B.timed_run(scene)
    num.update(reactions=[inc.reactions["block_top"].tolist() for inc in result.increments],
               rss_per_rank=MPI.COMM_WORLD.allgather(B.peak_rss_mib()))
    B.emit(num)


def report(runs: list[dict], machine: dict, load_end: float, foundation: str, slide: int,
           quick: bool) -> str:
    import numpy as np
    ref = np.asarray(runs[0]["reactions"][-1])
    out = [
        "`benchmarks/bench_condensed.py`" + (" --quick" if quick else "") + f": a block "
        f"({'x'.join(map(str, BLOCK))} hexahedra) on a deep foundation ({foundation}), "
        f"{runs[0]['dofs']:,} dofs, mu = 0.3, K = 50 E, press 1 + slide {slide} increments, "
        "MUMPS with the kept factorisation where it pays; each row one `mpirun -n` run.",
        "",
        f"* {B.machine_line(machine, load_end)}",
        "* seconds: the slowest rank's; wall = the solver's timers, CPU = process CPU time "
        "of the same intervals.  The machine is shared: the load average is listed with "
        "every run, and the wall times are noisy.",
        "",
    ]
    rows = []
    for run in runs:
        ls = run.get("linear_solves") or {}
        dr = float(np.linalg.norm(np.asarray(run["reactions"][-1]) - ref) / np.linalg.norm(ref))
        rows.append([run["label"], run["ranks"], run["newton"],
                     ls.get("preconditioner_setups", "-"), ls.get("krylov_iterations", "-"),
                     ls.get("condensed_solves", "-"),
                     f"{run['phases_wall']['linear_solve']:.3g} / "
                     f"{run['phases']['linear_solve']:.3g}",
                     f"{run['wall']:.3g} / {run['cpu']:.3g}", f"{dr:.1e}",
                     f"{run['load'][0]:.1f} -> {run['load'][1]:.1f}"])
    out.append(B.table(["package", "ranks", "Newton its", "factorisations", "Krylov its",
                        "condensed solves", "linear solve wall / CPU [s]",
                        "total wall / CPU [s]", "last reaction vs first row", "load"], rows,
                       "lrrrrrrrrr"))
    return "\n".join(out)


def main(argv=None) -> None:
    ap = B.worker_parser(__doc__)
    ap.add_argument("--foundation", help="foundation hexahedra, e.g. 24x24x36 (quick: 10x10x12)")
    ap.add_argument("--slide", type=int, default=3, help="slide increments")
    ap.add_argument("--ranks", default="1,2")
    ap.add_argument("--label", default="this commit", help="the package's name in the table")
    ap.add_argument("--json", help="write the runs to this file as they finish")
    ap.add_argument("--load", action="append", default=[], metavar="JSON",
                    help="report runs saved with --json instead of running (repeatable)")
    args = ap.parse_args(argv)
    if args.worker:
        return worker(args.worker)
    foundation = args.foundation or ("10x10x12" if args.quick else "24x24x36")
    machine = B.machine()
    runs: list[dict] = []
    for saved in args.load:
        runs += json.loads(Path(saved).read_text())
    if not args.load:
        mesh(tuple(int(x) for x in foundation.split("x")))  # built here, not by the ranks
        for r in (int(x) for x in args.ranks.split(",")):
            run = B.run_worker(Path(__file__), [foundation, str(args.slide)], ranks=r,
                               timeout=3 * 3600)
            run["label"] = args.label
            runs.append(run)
            print(f"{r} rank(s): dofs {run['dofs']} its {run['newton']} "
                  f"{run['linear_solves']} solve {run['phases_wall']['linear_solve']:.2f} s "
                  f"wall {run['wall']:.1f} s cpu {run['cpu']:.1f} s load {run['load']}",
                  flush=True)
            if args.json:
                Path(args.json).write_text(json.dumps(runs, indent=1))
    text = report(runs, machine, B.load_average(), foundation, args.slide, args.quick)
    print(text)
    if not args.no_results:
        B.write_section("The condensed path under MPI", text)


if __name__ == "__main__":
    sys.exit(main())
