"""Strong scaling, 1 vs 2 MPI ranks, on a 3D frictional scene of >= 2e5 dofs.

    python benchmarks/bench_scaling.py            # n = 18: ~2.6e5 dofs (long: tens of minutes)
    python benchmarks/bench_scaling.py --quick    # n = 5: ~9e3 dofs (< 2 min)
    python benchmarks/bench_scaling.py --n 12 --ranks 1,2 --no-results

The script starts itself under ``mpirun -n 1`` and ``mpirun -n 2`` (``--bind-to none``; the
Open MPI root variables are set) as worker processes, alternately, ``--repeat`` times each
(default 1), and compares them.  Scene: ``bench_cost.py``'s block on a foundation at
resolution n, mu = 0.3, K = 50 E, press 1 increment + slide ``--slide`` increments (default
1), MUMPS (distributed factorisation; the ordering is computed sequentially: this MUMPS has
neither ParMETIS nor PT-Scotch).  Each run reports, for the slowest rank, the wall and CPU
seconds of every phase (set-up, contact search, contact assembly, bulk assembly, linear
solve) and of the whole run, and the peak memory per rank.

Speedup = time on 1 rank / time on 2 ranks, per phase and in total, from wall time (the
definition) and from CPU time.  On a machine shared with other jobs the wall-time speedup
measures the share of the 2 cores the job got as much as the code: the load average is
given with each run.  Target: >= 1.7x on 2 ranks.  ``--solver iterative`` (or ``auto``)
runs the scene with GMRES + GAMG instead of MUMPS (its own RESULTS.md section).
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import _bench as B  # noqa: I001
import _meshes as M

import bench_cost as C

PHASES = ("setup", "contact_search", "contact_assembly", "bulk_assembly", "linear_solve")


def scene(n: int, slide: int, linear: str):
    """bench_cost's scene with ``[solver] linear``."""
    from dataclasses import replace

    from dolfinx_friction.scene.model import SolverSettings
    return replace(C.scene(n, True, slide_increments=slide), solver=SolverSettings(linear))


def worker(args: list[str]) -> None:
    from mpi4py import MPI
    n, slide, linear = int(args[0]), int(args[1]), args[2]
    comm = MPI.COMM_WORLD
    if len(args) > 3 and args[3] == "profile":
        (result, num), rows = B.profile_call(lambda: B.timed_run(scene(n, slide, linear)), top=14)
        num["profile_per_rank"] = comm.allgather(rows)
    else:
        result, num = B.timed_run(scene(n, slide, linear))
    num.update(n=n, reactions=[inc.reactions["block_top"].tolist() for inc in result.increments],
               rss_per_rank=comm.allgather(B.peak_rss_mib()))
    B.emit(num)


def chart(runs: dict, machine: dict, n: int, linear: str = "direct") -> Path:
    plt = B.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), dpi=100)
    ranks = sorted(runs)
    keys = list(PHASES) + ["total"]
    width = 0.8 / len(ranks)
    for ax, clock in ((axes[0], "wall"), (axes[1], "cpu")):
        for i, r in enumerate(ranks):
            run = best(runs[r], clock)
            vals = [phase(run, k, clock) for k in keys]
            ax.bar([j + i * width for j in range(len(keys))], vals, width,
                   label=f"{r} rank{'s' if r > 1 else ''} (load {run['load'][0]:.1f})")
        if 1 in runs and 2 in runs:
            for j, k in enumerate(keys):
                s = phase(best(runs[1], clock), k, clock) / max(phase(best(runs[2], clock), k,
                                                                      clock), 1e-12)
                top = max(phase(best(runs[r], clock), k, clock) for r in ranks)
                ax.text(j + width / 2, top * 1.02, f"{s:.2f}x", ha="center", fontsize=8)
        ax.set_xticks([j + width * (len(ranks) - 1) / 2 for j in range(len(keys))])
        ax.set_xticklabels([k.replace("_", "\n") for k in keys], fontsize=8)
        ax.set_ylabel(f"{clock} seconds (slowest rank)")
        ax.set_title(f"{clock} time per phase; speedup 1 -> 2 ranks on top", fontsize=10)
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3, axis="y")
    dofs = best(runs[ranks[0]], "wall")["dofs"]
    return B.save_figure(fig, "scaling.png" if linear == "direct" else f"scaling_{linear}.png",
                         f"strong scaling, two_boxes n = {n}, {dofs:,} dofs, mu = 0.3, "
                         + ("MUMPS" if linear == "direct" else f"[solver] {linear}"), machine)


def phase(run: dict, key: str, clock: str) -> float:
    if key == "total":
        return run["wall"] if clock == "wall" else run["cpu"]
    return (run["phases_wall"] if clock == "wall" else run["phases"])[key]


def best(runs: list[dict], clock: str) -> dict:
    return min(runs, key=lambda r: r["wall"] if clock == "wall" else r["cpu"])


def report(runs, machine, load_end, quick, figure, n, slide, linear="direct") -> str:
    some = next(iter(runs.values()))[0]
    out = [
        "`benchmarks/bench_scaling.py`" + (" --quick" if quick else "") + f": block on a "
        f"foundation (`bench_cost.py`'s scene, n = {n}, {some['dofs']:,} dofs), mu = 0.3, "
        f"press 1 + slide {slide} increment(s), "
        + ("MUMPS" if linear == "direct" else f"[solver] linear = {linear!r} (GMRES + GAMG above "
                                              "120k dofs)")
        + "; the script runs itself under "
        "`mpirun -n 1` and `mpirun -n 2` (`--bind-to none`).",
        "",
        f"* {B.machine_line(machine, load_end)}",
        "* per phase: the slowest rank's seconds; wall = the solver's own timers, CPU = the "
        "same intervals in process CPU time (Open MPI busy-waits, so a rank waiting for the "
        "other one still burns CPU).  With other jobs on the 2 cores the wall-time speedup is "
        "bounded by the cores the job got; the load average is listed with every run.",
        "",
    ]
    trs = []
    for r in sorted(runs):
        for run in runs[r]:
            krylov = (run.get("linear_solves") or {}).get("krylov_iterations")
            trs.append([r, f"{run['dofs']:,}", run["newton"], "-" if krylov is None else krylov]
                       + [f"{phase(run, k, 'wall'):.3g} / {phase(run, k, 'cpu'):.3g}"
                          for k in list(PHASES) + ["total"]]
                       + [" / ".join(f"{x:.0f}" for x in run["rss_per_rank"]),
                          f"{run['load'][0]:.1f} -> {run['load'][1]:.1f}"])
    out.append(B.table(["ranks", "dofs", "Newton its", "Krylov its"]
                       + [f"{k.replace('_', ' ')} wall / CPU [s]" for k in PHASES]
                       + ["total wall / CPU [s]", "peak RSS per rank [MiB]", "load"], trs))
    out.append("")
    if 1 in runs and 2 in runs:
        rows = []
        for k in list(PHASES) + ["total"]:
            rows.append([k.replace("_", " ")]
                        + [f"{phase(best(runs[1], c), k, c) / max(phase(best(runs[2], c), k, c), 1e-12):.2f}x"
                           for c in ("wall", "cpu")])
        out.append(B.table(["phase", "speedup (wall)", "speedup (CPU)"], rows))
        out.append("")
        sw = phase(best(runs[1], "wall"), "total", "wall") / phase(best(runs[2], "wall"),
                                                                   "total", "wall")
        sc = phase(best(runs[1], "cpu"), "total", "cpu") / phase(best(runs[2], "cpu"),
                                                                 "total", "cpu")
        r1 = [x["reactions"][-1] for x in runs[1]][0]
        r2 = [x["reactions"][-1] for x in runs[2]][0]
        import numpy as np
        dr = float(np.linalg.norm(np.subtract(r1, r2)) / np.linalg.norm(r1))
        out.append(f"Target: >= 1.7x on 2 ranks (wall time).  Measured total speedup: {sw:.2f}x (wall), "
                   f"{sc:.2f}x (CPU) -- " + ("**met**" if sw >= 1.7 else "**missed**")
                   + f".  Final reaction, 1 vs 2 ranks: relative difference {dr:.1e}.")
        out.append("")
    out.append(f"Chart: `benchmarks/figures/{figure.name}`.")
    return "\n".join(out)


def main(argv=None) -> None:
    ap = B.worker_parser(__doc__)
    ap.add_argument("--n", type=int, help="two_boxes resolution (default 18; quick: 5)")
    ap.add_argument("--slide", type=int, default=1, help="slide increments")
    ap.add_argument("--solver", default="direct", choices=("direct", "iterative", "auto"),
                    help="[solver] linear of the scene (default direct: MUMPS)")
    ap.add_argument("--ranks", default="1,2")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--json", help="write the runs to this file as they finish")
    ap.add_argument("--load", action="append", default=[], metavar="JSON",
                    help="report runs saved with --json instead of running (repeatable; "
                         "later files replace the rank counts they contain)")
    ap.add_argument("--profile", action="store_true",
                    help="run the largest rank count once more under cProfile (every rank) and "
                         "add the profiles to the report")
    ap.add_argument("--profile-n", type=int, help="resolution of the profiled run (default: n)")
    args = ap.parse_args(argv)
    if args.worker:
        return worker(args.worker)
    n = args.n or (5 if args.quick else 18)
    C.two_boxes_mesh(n)  # built here, not by the ranks at once
    print(f"two_boxes n = {n}: {M.two_boxes_dofs(n):,} dofs")
    machine = B.machine()
    runs: dict[int, list[dict]] = {}
    for saved in args.load:
        runs.update({int(r): v for r, v in json.loads(Path(saved).read_text()).items()})
    if not args.load:
        runs = B.rank_series(
            Path(__file__), {int(r): [str(n), str(args.slide), args.solver]
                             for r in args.ranks.split(",")},
            lambda r, run: f"{r} rank(s): dofs {run['dofs']} its {run['newton']} wall "
                           f"{run['wall']:.1f} s cpu {run['cpu']:.1f} s phases(wall) "
                           + " ".join(f"{k}={run['phases_wall'][k]:.2f}" for k in PHASES)
                           + f" rss {run['rss_per_rank']} load {run['load']}",
            args.repeat, args.json)
    figure = chart(runs, machine, n, args.solver)
    text = report(runs, machine, B.load_average(), args.quick, figure, n, args.slide,
                  args.solver)
    if args.profile:
        r, pn = max(runs), args.profile_n or n
        C.two_boxes_mesh(pn)
        prof = B.run_worker(Path(__file__), [str(pn), str(args.slide), args.solver, "profile"],
                            ranks=r,
                            timeout=6 * 3600)
        for k, rows in enumerate(prof["profile_per_rank"]):
            t = B.profile_table(rows, f"Profile, n = {pn} ({prof['dofs']:,} dofs), {r} ranks, "
                                      f"rank {k} (wall {prof['wall']:.0f} s, load "
                                      f"{prof['load'][0]:.1f}), ")
            print(t)
            text += "\n\n" + t
    print(text)
    if not args.no_results:
        B.write_section("Strong scaling, 1 vs 2 ranks"
                        + ("" if args.solver == "direct" else f" ([solver] {args.solver})"), text)


if __name__ == "__main__":
    sys.exit(main())
