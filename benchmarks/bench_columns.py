"""Columns of ``K^-1`` against a factorisation: the price of the condensed path's ``G``.

    python benchmarks/bench_columns.py                  # RESULTS.md section
    python benchmarks/bench_columns.py --quick --no-results

:class:`~dolfinx_friction.nls.linear.Condensed` weighs every cost in MUMPS's flop counts:
a factorisation's (RINFOG(3)) against 4 flops per factor entry (INFOG(20)) for a
back-solve; the columns of ``G`` are computed
:data:`~dolfinx_friction.nls.linear.COLUMNS_PER_SOLVE` at a time (dense right-hand
sides) and priced at :data:`~dolfinx_friction.nls.linear.COLUMN_SHARE` of a back-solve.
This bench measures what the counts do not see, the flop rates: on the held elastic
stiffness of ``bench_factor.py`` (P1; unit square of triangles, unit cube of hexahedra;
serial, one thread), CPU time of MUMPS LU's numeric factorisation (the same matrix, new
values), of one back-solve, and per column of a back-solve with 64 right-hand sides; least
of ``--repeats``.  ``share`` is the price that makes a column's flops cost what it takes in
time, measured in factorisations: ``(t_column / t_factorisation) x (flops_factorisation /
flops_back-solve)``.
"""
from __future__ import annotations

import sys
import time

import _bench as B  # noqa: I001
import numpy as np

import bench_factor

SIZES = {2: [10, 24, 54, 80], 3: [3, 4, 6, 8, 12, 16]}
QUICK = {2: [24], 3: [4, 8]}


def least(fn, repeats: int) -> float:
    """Least CPU seconds of ``fn()`` over ``repeats`` calls."""
    times = []
    for _ in range(repeats):
        t = time.process_time()
        fn()
        times.append(time.process_time() - t)
    return min(times)


def measure(K, repeats: int) -> dict:
    """Flops and CPU seconds of MUMPS LU on ``K``: numeric factorisation, one back-solve,
    one column among 64 right-hand sides."""
    from petsc4py import PETSc
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    ksp.setOperators(K, K)
    ksp.setUp()
    F = ksp.getPC().getFactorMatrix()
    flops, entries = F.getMumpsRinfog(3), F.getMumpsInfog(20)
    entries = entries if entries >= 0 else -entries * 1e6

    def factorise():
        K.scale(1.0 + 1e-9)  # new values, same pattern: a numeric factorisation
        ksp.setOperators(K, K)
        ksp.setUp()

    b, x = K.createVecs()
    b.setRandom()
    n, width = K.getSize()[0], 64
    rhs = PETSc.Mat().createDense((n, width), array=np.asfortranarray(
        np.random.default_rng(0).random((n, width))), comm=PETSc.COMM_SELF)
    X = PETSc.Mat().createDense((n, width), comm=PETSc.COMM_SELF)
    X.setUp()
    row = {"dofs": n, "flops": flops, "solve_flops": 4.0 * entries,
           "factorise": least(factorise, repeats),
           "solve": least(lambda: ksp.solve(b, x), repeats),
           "column": least(lambda: F.matSolve(rhs, X), repeats) / width}
    for obj in (rhs, X, b, x, ksp):
        obj.destroy()
    row["share"] = row["column"] / row["factorise"] * row["flops"] / row["solve_flops"]
    return row


def main(argv=None) -> None:
    args = bench_factor.arguments(argv, __doc__)
    from dolfinx_friction.nls.linear import COLUMN_SHARE
    machine = B.machine()
    rows = []
    for gdim, ns in (QUICK if args.quick else SIZES).items():
        for n in ns:
            K, _ = bench_factor.stiffness(gdim, n)
            r = measure(K, args.repeats)
            K.destroy()
            rate = {k: r[f] / r[k] / 1e9 for k, f in
                    (("factorise", "flops"), ("solve", "solve_flops"),
                     ("column", "solve_flops"))}
            rows.append([f"{gdim}D", f"{r['dofs']:,}", f"{r['flops']:.3g}",
                         f"{1e3 * r['factorise']:.2f}", f"{1e3 * r['solve']:.3f}",
                         f"{1e3 * r['column']:.4f}", f"{rate['factorise']:.1f}",
                         f"{rate['solve']:.1f}", f"{rate['column']:.1f}",
                         f"{r['factorise'] / r['column']:.0f}",
                         f"{r['flops'] / r['solve_flops']:.0f}", f"{r['share']:.2f}"])
            print(*rows[-1], flush=True)
    shares = [float(r[-1]) for r in rows]
    text = (f"`benchmarks/bench_columns.py`: {B.machine_line(machine, B.load_average())}.\n\n"
            "MUMPS LU (serial, one thread) on the held elastic stiffness of "
            "`bench_factor.py`: CPU milliseconds, least of "
            f"{args.repeats}, of a numeric factorisation, one back-solve and one column "
            "among 64 right-hand sides (what `Condensed` computes `G` with); GFlop/s by "
            "MUMPS's counts (a back-solve: 4 flops per factor entry); `columns per "
            "factorisation` in time and in the counts; `share`: the price of a column, in "
            "back-solve flops, at which the counts say what the clock does.\n\n"
            + B.table(["dim", "dofs", "factorisation flops", "factorise [ms]",
                       "back-solve [ms]", "column of 64 [ms]", "GFlop/s factorise",
                       "GFlop/s back-solve", "GFlop/s column", "columns per factorisation",
                       "back-solves per factorisation (flops)", "share"], rows)
            + f"\n\nThe measured share runs from {min(shares):.2f} to {max(shares):.2f} "
            f"(the smaller the matrix, the smaller); the condensed path prices a column at "
            f"{COLUMN_SHARE} of a back-solve (`nls.linear.COLUMN_SHARE`).")
    print(text)
    if not args.no_results:
        B.write_section("Columns of K^-1 against a factorisation: the condensed path's price",
                        text, keep=("The price in use",))


if __name__ == "__main__":
    sys.exit(main())
