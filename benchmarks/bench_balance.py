"""The balance of every accepted increment, and what checking it costs.

    python benchmarks/bench_balance.py                 # every demo scene + the reproducer
    python benchmarks/bench_balance.py --no-results    # print, leave RESULTS.md alone
    python benchmarks/bench_balance.py --scenes ironing,incline

Every scene of ``demos/*.toml`` and the issue-23 reproducer (the ironing demo with its die
10^7 times stiffer and ``newton_rtol = 1e-6``, press step only) is solved in memory, one
rank.  At each accepted increment: the largest force left unbalanced on a body along an
axis (:meth:`BlockProblem.imbalance`), against the size of the forces
(:meth:`BlockProblem.force_scale`) and against the postcondition's bound (sqrt(n) times
:meth:`Newton.residual_tolerance`, n the body's free rows along the axis).  The cost: the CPU
time of :meth:`BlockProblem.postcondition` (as ``solve_steps`` calls it) against the run's.
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import time

import _bench  # noqa: F401  (one thread per process; paths)
import numpy as np
from mpi4py import MPI

from _bench import DEMOS, machine, machine_line, table, write_section
from dolfinx_friction.fem.block_problem import BlockProblem
from dolfinx_friction.scene.build import ContactProblem
from dolfinx_friction.scene.driver import Solver
from dolfinx_friction.scene.toml import load_scene

REPRODUCER = ("ironing, die E x 10^4, rtol 1e-6 (press)",
              ["body.1.E=1e8", "step.0.newton_rtol=1e-6", "step.0.increments=10"])


def measure(scene) -> dict:
    """Worst ratios and the check's share of the run's CPU time."""
    spent = [0.0]
    check = BlockProblem.postcondition

    def timed(self, tolerance):
        start = time.process_time()
        try:
            return check(self, tolerance)
        finally:
            spent[0] += time.process_time() - start
    BlockProblem.postcondition = timed
    try:
        solver = Solver(ContactProblem(scene, MPI.COMM_WORLD))
        system, rows = solver.system, []

        def seen(inc):
            bound = solver.newton.residual_tolerance(system) * np.sqrt(system.free_rows().max())
            rows.append((inc.imbalance / inc.force if inc.force else 0.0, inc.imbalance / bound))
        start = time.process_time()
        summary = solver.run(seen)
        cpu = time.process_time() - start
    finally:
        BlockProblem.postcondition = check
    ratios = np.array(rows)
    return {"increments": summary.increments, "cutbacks": summary.cutbacks,
            "force": ratios[:, 0].max(), "bound": ratios[:, 1].max(), "cpu": cpu,
            "check": spent[0]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default="", help="comma-separated demo names")
    parser.add_argument("--no-results", action="store_true")
    args = parser.parse_args()
    names = sorted(p.stem for p in DEMOS.glob("*.toml"))
    if args.scenes:
        names = [n for n in names if n in args.scenes.split(",")]
    m = machine()
    rows = []
    cases = [(n, load_scene(DEMOS / f"{n}.toml")) for n in names]
    if not args.scenes or "reproducer" in args.scenes:
        scene = load_scene(DEMOS / "ironing.toml", REPRODUCER[1])
        cases.append((REPRODUCER[0], dataclasses.replace(scene, steps=scene.steps[:1])))
    for name, scene in cases:
        r = measure(scene)
        rows.append([name, r["increments"], r["cutbacks"], f"{r['force']:.1e}",
                     f"{r['bound']:.1e}", f"{r['cpu']:.2f}", f"{100 * r['check'] / r['cpu']:.2f} %"])
        print(rows[-1], flush=True)
    body = (f"`benchmarks/bench_balance.py`: {machine_line(m, os.getloadavg()[0])}; "
            "one rank.\n\nThe largest force left unbalanced on a body along an axis at an "
            "accepted increment, against the size of the forces (the largest 2-norm of the "
            "reactions, loads and contact forces) and against the postcondition's bound "
            "(sqrt(n) times the residual norm the convergence test accepts); the CPU time of "
            "the postcondition against the run's (in-memory runs, no output written).\n\n"
            + table(["scene", "increments", "cutbacks", "worst imbalance / forces",
                     "worst imbalance / bound", "run CPU [s]", "check's share"], rows))
    print(body)
    if not args.no_results:
        write_section("Balance of the accepted increments", body)


if __name__ == "__main__":
    main()
