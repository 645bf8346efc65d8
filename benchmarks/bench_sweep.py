"""A study of a small scene: a 10-point sweep of mu against CalculiX running the 10 decks.

    python benchmarks/bench_sweep.py                         # RESULTS.md section
    python benchmarks/bench_sweep.py --before 2b5918c        # and that commit's sweeps
    python benchmarks/bench_sweep.py --repeats 1 --no-results

The scene is ``bench_small.py``'s ``boxes`` (a block pressed onto a foundation and slid,
801 dofs, 1 + 10 increments, K and lambda by CalculiX's rules) at mu = 0.05, 0.10, ...,
0.50.  Timed in rounds (``--repeats``, default 3), each command once per round, one after
the other, each as a user runs it (wall time of the whole command, start-up included; CPU
of the child processes); the least wall and the least CPU over the rounds are reported
(the machine is shared: the least disturbed run):

* ``sweep -j 1`` and ``sweep -j 2``: ``dolfinx-friction sweep boxes.toml --set
  contact.0.mu=...`` (warm worker processes, one per job); with ``--before COMMIT`` the
  same two at that commit (exported by ``git archive`` into ``$BENCH_WORK/trees``);
* ``fresh runs``: ``dolfinx-friction run --set contact.0.mu=... --quiet`` once per point;
* ``ccx``: ``ccx -i`` on each of the 10 decks (one thread), one after the other.

Asserted: every point's final reactions in the sweeps equal the fresh run's to 1e-12
relative (the same computation; bit for bit so far), and CalculiX's within 0.5 %
(bench_ccx measured 0.037 % on this scene).

Then where a warm point's CPU goes, for this tree and the ``--before`` one: a process per
tree (``--point-worker``) runs the 10 points one after the other in-process, as a sweep's
worker does (``run(..., workspace=...)``, all outputs), twice; per point the CPU of the
whole ``run()`` and of each phase (the run's own timers); the least over the second pass.
"""
from __future__ import annotations

import argparse
import csv
import os
import subprocess
import sys
import time

import _bench as B  # noqa: I001
import numpy as np

import bench_small as S

MUS = [round(0.05 * k, 2) for k in range(1, 11)]


def timed(cmd: list[str], cwd, env) -> tuple[float, float]:
    w0, c0 = time.perf_counter(), B.children_cpu()
    subprocess.run(cmd, cwd=cwd, env=env, check=False, capture_output=True)
    return time.perf_counter() - w0, B.children_cpu() - c0


def final_reaction(history) -> np.ndarray:
    with open(history, newline="") as f:
        last = list(csv.DictReader(f))[-1]
    return np.array([float(last[f"R_block_top_{a}"]) for a in "xyz"])


PHASES = ("linear_solve", "output", "contact_search", "contact_assembly", "bulk_assembly",
          "setup")


def point_worker(toml: str) -> None:
    """Run the 10 points twice in this process (warm, as a sweep's worker); print the least
    CPU of a whole point and of each phase over the second pass (JSON)."""
    import json
    import time as clock

    from dolfinx_friction.scene.runner import run
    from dolfinx_friction.scene.workspace import Workspace
    workspace, best = Workspace(), {}
    for round_ in range(2):
        for mu in MUS:
            start = clock.process_time()
            result = run(toml, out=f"warm_{mu}", overrides=[f"contact.0.mu={mu}"],
                         workspace=workspace)
            cpu = {"point": clock.process_time() - start, **{
                phase: result.solver.timers.cpu[phase] for phase in PHASES}}
            if round_:
                best = {k: min(v, best.get(k, v)) for k, v in cpu.items()}
            del result
    print(json.dumps(best))


def breakdown(toml, env) -> dict:
    """The least CPU of a warm point and of its phases (seconds), by ``--point-worker``."""
    import json
    out = subprocess.run([B.PYTHON, __file__, "--point-worker", toml.name], cwd=toml.parent,
                         env=env, check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main(argv=None) -> None:
    if argv is None and sys.argv[1:2] == ["--point-worker"]:
        return point_worker(sys.argv[2])
    from dolfinx_friction.reference import calculix
    from dolfinx_friction.scene.toml import load_scene
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", metavar="COMMIT", help="time that commit's sweeps too")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--no-results", action="store_true")
    args = ap.parse_args(argv)
    toml = S.prepare("boxes")
    d, py = toml.parent, B.PYTHON
    env = dict(os.environ, PYTHONPATH=str(B.ROOT), OMP_NUM_THREADS="1",
               DOLFINX_FRICTION_CACHE=str(B.work_dir("small") / "mesh_cache"))
    values = ",".join(str(m) for m in MUS)
    decks = []
    for mu in MUS:
        inp = d / f"boxes_mu{mu}.inp"
        calculix.write_inp(load_scene(toml, [f"contact.0.mu={mu}"]), inp)
        decks.append(inp)
    trees = {"": env}
    if args.before:
        trees[f" at {args.before}"] = dict(env, PYTHONPATH=str(B.export(args.before)))
        timed([py, "-m", "dolfinx_friction", "run", toml.name, "--quiet", "--out",
               "warm_up"], d, trees[f" at {args.before}"])  # (numba's cache of that tree)
    sweeps = {f"sweep -j {jobs}{tree}": (jobs, e) for tree, e in trees.items()
              for jobs in (1, 2)}
    machine = B.machine()  # (the load at the start)
    times: dict[str, list] = {}
    for _ in range(args.repeats):
        for key, (jobs, e) in sweeps.items():
            out = d / f"sweep_j{jobs}{'_before' if e is not env else ''}"
            times.setdefault(key, []).append(timed(
                [py, "-m", "dolfinx_friction", "sweep", toml.name, "--set",
                 f"contact.0.mu={values}", "-j", str(jobs), "--out", out.name, "--quiet"],
                d, e))
        w0, c0 = time.perf_counter(), B.children_cpu()
        for mu in MUS:
            subprocess.run([py, "-m", "dolfinx_friction", "run", toml.name, "--quiet", "--out",
                            f"fresh_mu{mu}", "--set", f"contact.0.mu={mu}"], cwd=d, env=env,
                           check=True, capture_output=True)
        times.setdefault("fresh runs", []).append(
            (time.perf_counter() - w0, B.children_cpu() - c0))
        w0, c0 = time.perf_counter(), B.children_cpu()
        ccx = [calculix.run_ccx(inp, details=True, threads=1) for inp in decks]
        times.setdefault("ccx", []).append((time.perf_counter() - w0, B.children_cpu() - c0))
    points = {tree or " (this tree)": breakdown(toml, e) for tree, e in trees.items()}
    load1 = B.load_average()
    rows = {k: (min(w for w, _ in v), min(c for _, c in v)) for k, v in times.items()}
    worst_fresh, worst_ccx = 0.0, 0.0
    for mu, result in zip(MUS, ccx):
        fresh = final_reaction(d / f"fresh_mu{mu}" / "history.csv")
        for folder in {f"sweep_j{jobs}{'_before' if e is not env else ''}"
                       for jobs, e in sweeps.values()}:
            swept = final_reaction(d / folder / f"contact.0.mu={mu}" / "history.csv")
            worst_fresh = max(worst_fresh, np.abs(swept - fresh).max() / np.abs(fresh).max())
        steps = result.reactions
        last = steps[max(steps)]
        theirs = np.asarray(last[max(last)]["block_top"])
        worst_ccx = max(worst_ccx, np.linalg.norm(fresh - theirs) / np.linalg.norm(theirs))
    assert worst_fresh <= 1e-12, worst_fresh
    assert worst_ccx <= 5e-3, worst_ccx
    ccx_wall, ccx_cpu = rows["ccx"]
    table = [[key, f"{wall:.2f}", f"{cpu:.2f}", f"{wall / ccx_wall:.2f}", f"{cpu / ccx_cpu:.2f}"]
             for key, (wall, cpu) in rows.items()]
    text = (f"`benchmarks/bench_sweep.py`: {B.machine_line(machine, load1)}.\n\n"
            "A 10-point sweep of mu (0.05 to 0.50) of bench_small's `boxes` scene (801 dofs, "
            "1 + 10 increments) as a user runs it, start-up included, against `ccx` on the 10 "
            "decks one after the other, in the same call, in rounds (least wall and least CPU "
            f"over {args.repeats} rounds).  Every point's final reactions: sweep = fresh run "
            f"(worst {worst_fresh:.1e} relative), CalculiX within {100 * worst_ccx:.3f} %.\n\n"
            + B.table(["command", "wall [s]", "CPU [s]", "wall / ccx", "CPU / ccx"], table)
            + "\n\nA warm point (in-process, as in a sweep's worker, all outputs): least CPU "
            "over the 10 points of a second pass, seconds; phases by the run's timers, "
            "`point` the whole `run()`; ccx's CPU per deck "
            f"{ccx_cpu / len(MUS):.3f} s:\n\n"
            + B.table(["tree", "point", *PHASES],
                      [[tree.strip(), *(f"{cpu[k]:.3f}" for k in ("point", *PHASES))]
                       for tree, cpu in points.items()]))
    print(text)
    if not args.no_results:
        B.write_section("Studies: a 10-point sweep against ccx", text)


if __name__ == "__main__":
    sys.exit(main())
