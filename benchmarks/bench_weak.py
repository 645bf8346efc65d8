"""Weak scaling, 1 vs 2 MPI ranks: the same scene with the dofs per rank held constant.

    python benchmarks/bench_weak.py              # n = 10 on 1 rank (67k dofs), n = 14 (133k) on 2
    python benchmarks/bench_weak.py --quick      # n = 5 on 1 rank (9k dofs) (< 2 min)
    python benchmarks/bench_weak.py --n 10 --no-results

Scene: ``bench_cost.py``'s block on a foundation, mu = 0.3, K = 50 E, press 1 increment +
slide ``--slide`` increments (default 1), ``[solver] linear = "iterative"`` (GMRES + GAMG:
the solver that scales; MUMPS's ordering is sequential here).  On 1 rank at resolution n,
on 2 ranks at the n' whose mesh has the dofs nearest twice as many (the block and the
foundation refined alike: the contact surface grows as dofs^(2/3), so the surface per rank
shrinks by 2^(1/3) from 1 to 2 ranks).  The script starts itself under ``mpirun`` (as
``bench_scaling.py``), ``--repeat`` times each, alternately.

Reported per Newton iteration (phase / Newton iterations; the slowest rank): wall and CPU
seconds of contact search, contact assembly, bulk assembly and linear solve; and per rank
what the pairing exchanged (:meth:`NodeToSurface.exchange`): master faces and bytes sent to
and received from the other rank per search, the bounding boxes' allgather, the
displacement values each evaluation gathers from the other rank.  Weak-scaling efficiency =
time per iteration on 1 rank / on 2 ranks (1 is ideal); with other jobs on the 2 cores the
wall times measure the share of the cores the job got as much as the code: the load average
is given with each run.  The model for 64-1024 ranks built on these numbers is
``docs/parallel.md``.
"""
from __future__ import annotations

import json
import math
import sys
from dataclasses import asdict
from pathlib import Path

import _bench as B  # noqa: I001
import _meshes as M

import bench_cost as C

PHASES = ("contact_search", "contact_assembly", "bulk_assembly", "linear_solve")
EXCHANGE = ("searches", "box_bytes", "faces_sent", "face_bytes_sent", "faces_received",
            "face_bytes_received", "faces", "gathered")


def scene(n: int, slide: int):
    """bench_cost's scene with GMRES + GAMG."""
    from dataclasses import replace

    from dolfinx_friction.scene.model import SolverSettings
    return replace(C.scene(n, True, slide_increments=slide), solver=SolverSettings("iterative"))


def worker(args: list[str]) -> None:
    from mpi4py import MPI
    n, slide = int(args[0]), int(args[1])
    comm = MPI.COMM_WORLD
    result, num = B.timed_run(scene(n, slide))
    system = result.problem.system
    exchange = [asdict(c.exchange()) for c in system.contacts]
    num.update(n=n, exchange_per_rank=comm.allgather(exchange[0]),
               dofs_per_rank=comm.allgather(int(system.x.getLocalSize())),
               slaves_per_rank=comm.allgather(len(system.contacts[0].state().gap)),
               reactions=[inc.reactions["block_top"].tolist() for inc in result.increments])
    B.emit(num)


def twice(n: int) -> int:
    """The resolution whose two_boxes mesh has the dofs nearest (in ratio) twice n's."""
    target = 2 * M.two_boxes_dofs(n)
    return min(range(n + 1, 2 * n + 1), key=lambda m: abs(math.log(M.two_boxes_dofs(m) / target)))


def per_iteration(run: dict, key: str, clock: str) -> float:
    phases = run["phases_wall"] if clock == "wall" else run["phases"]
    its = max(run["newton"], 1)
    if key == "total":
        return sum(phases[k] for k in PHASES) / its
    return phases[key] / its


def best(runs: list[dict]) -> dict:
    return min(runs, key=lambda r: r["wall"])


def chart(runs: dict, machine: dict) -> Path:
    plt = B.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), dpi=100)
    ranks = sorted(runs)
    keys = list(PHASES) + ["total"]
    width = 0.8 / len(ranks)
    ax = axes[0]
    for i, r in enumerate(ranks):
        run = best(runs[r])
        ax.bar([j + i * width for j in range(len(keys))],
               [per_iteration(run, k, "wall") for k in keys], width,
               label=f"{r} rank{'s' if r > 1 else ''}: {run['dofs']:,} dofs "
                     f"(load {run['load'][0]:.1f})")
    ax.set_xticks([j + width * (len(ranks) - 1) / 2 for j in range(len(keys))])
    ax.set_xticklabels([k.replace("_", "\n") for k in keys], fontsize=8)
    ax.set_ylabel("wall seconds per Newton iteration (slowest rank)")
    ax.set_title("time per Newton iteration, dofs per rank constant", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, axis="y")
    ax = axes[1]
    for i, r in enumerate(ranks):
        run = best(runs[r])
        per = run["exchange_per_rank"]
        searches = max(per[0]["searches"], 1)
        values = [max(e["box_bytes"] for e in per) / searches / 1024,
                  max(e["face_bytes_sent"] for e in per) / searches / 1024,
                  max(8 * e["gathered"] for e in per) / 1024]
        ax.bar([j + i * width for j in range(3)], values, width, label=f"{r} rank(s)")
    ax.set_xticks([j + width * (len(ranks) - 1) / 2 for j in range(3)])
    ax.set_xticklabels(["boxes allgather\nper search", "master faces sent\nper search",
                        "displacements gathered\nper evaluation"], fontsize=8)
    ax.set_ylabel("KiB per rank (largest rank)")
    ax.set_title("what the pairing exchanges, per rank", fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, axis="y")
    return B.save_figure(fig, "weak_scaling.png", "weak scaling, two_boxes, mu = 0.3, GMRES + GAMG",
                         machine)


def report(runs: dict, machine: dict, load_end: float, quick: bool, figure: Path,
           slide: int) -> str:
    out = [
        "`benchmarks/bench_weak.py`" + (" --quick" if quick else "") + ": block on a "
        "foundation (`bench_cost.py`'s scene), mu = 0.3, press 1 + slide "
        f"{slide} increment(s), GMRES + GAMG (`[solver] linear = \"iterative\"`), the dofs "
        "per rank held constant: " + ", ".join(
            f"n = {best(runs[r])['n']} on {r} rank{'s' if r > 1 else ''} "
            f"({best(runs[r])['dofs']:,} dofs)" for r in sorted(runs))
        + "; the script runs itself under `mpirun` (`--bind-to none`).",
        "",
        f"* {B.machine_line(machine, load_end)}",
        "* per iteration: phase seconds of the slowest rank / Newton iterations; wall = the "
        "solver's timers, CPU = the same intervals in process CPU time.  The machine is "
        "shared: the load average is listed with every run and the wall times are noisy.",
        "* exchange: `NodeToSurface.exchange()` per rank (array bytes, no MPI envelope), "
        "per search; 'gathered' = displacement values fetched from the other rank at every "
        "contact evaluation.",
        "",
    ]
    rows = []
    for r in sorted(runs):
        for run in runs[r]:
            krylov = (run.get("linear_solves") or {}).get("krylov_iterations")
            rows.append([r, run["n"], f"{run['dofs']:,}",
                         " / ".join(f"{d:,}" for d in run["dofs_per_rank"]),
                         " / ".join(str(s) for s in run["slaves_per_rank"]), run["newton"],
                         "-" if krylov is None else krylov]
                        + [f"{per_iteration(run, k, 'wall'):.3g} / "
                           f"{per_iteration(run, k, 'cpu'):.3g}" for k in list(PHASES) + ["total"]]
                        + [f"{run['load'][0]:.1f} -> {run['load'][1]:.1f}"])
    out.append(B.table(["ranks", "n", "dofs", "dofs per rank", "slave nodes per rank",
                        "Newton its", "Krylov its"]
                       + [f"{k.replace('_', ' ')} /it wall / CPU [s]" for k in PHASES]
                       + ["total /it wall / CPU [s]", "load"], rows))
    out.append("")
    rows = []
    for r in sorted(runs):
        run = best(runs[r])
        for k, e in enumerate(run["exchange_per_rank"]):
            s = max(e["searches"], 1)
            rows.append([r, k, e["searches"], f"{e['box_bytes'] / s:,.0f}",
                         f"{e['faces_sent'] / s:,.0f}", f"{e['face_bytes_sent'] / s:,.0f}",
                         f"{e['faces_received'] / s:,.0f}", f"{e['face_bytes_received'] / s:,.0f}",
                         f"{e['faces']:,}", f"{e['gathered']:,}"])
    out.append(B.table(["ranks", "rank", "searches", "box allgather [B/search]",
                        "faces sent /search", "bytes sent /search", "faces received /search",
                        "bytes received /search", "faces held", "values gathered /evaluation"],
                       rows))
    out.append("")
    if 1 in runs and 2 in runs:
        one, two = best(runs[1]), best(runs[2])
        rows = [[k.replace("_", " ")] + [f"{per_iteration(one, k, c) / per_iteration(two, k, c):.2f}"
                                         for c in ("wall", "cpu")]
                for k in list(PHASES) + ["total"]]
        out.append(B.table(["phase", "efficiency t1/t2 (wall)", "efficiency t1/t2 (CPU)"], rows))
        out.append("")
    out.append(f"Chart: `benchmarks/figures/{figure.name}`.")
    return "\n".join(out)


def main(argv=None) -> None:
    ap = B.worker_parser(__doc__)
    ap.add_argument("--n", type=int, help="resolution on 1 rank (default 10; quick: 5)")
    ap.add_argument("--slide", type=int, default=1, help="slide increments")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--json", help="write the runs to this file as they finish")
    ap.add_argument("--load", help="report runs saved with --json instead of running")
    args = ap.parse_args(argv)
    if args.worker:
        return worker(args.worker)
    machine = B.machine()
    runs: dict[int, list[dict]] = {}
    if args.load:
        runs = {int(r): v for r, v in json.loads(Path(args.load).read_text()).items()}
    else:
        n1 = args.n or (5 if args.quick else 10)
        sizes = {1: n1, 2: twice(n1)}
        for r, n in sizes.items():
            C.two_boxes_mesh(n)  # built here, not by the ranks at once
            print(f"{r} rank(s): two_boxes n = {n}, {M.two_boxes_dofs(n):,} dofs", flush=True)
        runs = B.rank_series(
            Path(__file__), {r: [str(n), str(args.slide)] for r, n in sizes.items()},
            lambda r, run: f"{r} rank(s): n {sizes[r]} dofs {run['dofs']} its {run['newton']} "
                           f"wall {run['wall']:.1f} s per it(wall) "
                           + " ".join(f"{k}={per_iteration(run, k, 'wall'):.3f}" for k in PHASES)
                           + f" exchange {run['exchange_per_rank']} load {run['load']}",
            args.repeat, args.json)
    figure = chart(runs, machine)
    text = report(runs, machine, B.load_average(), args.quick, figure, args.slide)
    print(text)
    if not args.no_results:
        B.write_section("Weak scaling, 1 vs 2 ranks", text)


if __name__ == "__main__":
    sys.exit(main())
