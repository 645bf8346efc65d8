"""Direct solvers of small systems: MUMPS against PETSc's own and SuiteSparse's factorisations.

    python benchmarks/bench_factor.py                   # RESULTS.md section + chart
    python benchmarks/bench_factor.py --quick --no-results

Matrices: the linear-elastic stiffness (E = 1000, nu = 0.3, P1) of a unit square of
triangles (2D) and a unit cube of hexahedra (3D), one side held (its rows and columns
dropped, as :mod:`dolfinx_friction.nls.free_rows` solves), on a range of sizes.  The
unsymmetric case (friction's tangent): every value of the rows of the top face's dofs
scaled by 1 + 0.1 r, r uniform in [0, 1) (seeded), the pattern kept.  Each solver is a
``preonly`` KSP, serial, one thread, as :class:`~dolfinx_friction.nls.linear.LinearSolver`
sets it: its first solve (ordering, symbolic and numeric factorisation, back-solve) and a
repeated one (the same matrix object, values changed by a factor 1 + 1e-3: numeric
factorisation and back-solve, what a Newton iteration with an unchanged pattern costs).
CPU seconds, least over ``--repeats``; the relative residual of each solve is checked
(<= 1e-10).  The crossover (the largest size at which PETSc's LU, nested-dissection
ordering, costs no more than MUMPS in the repeated solve) sets
:data:`dolfinx_friction.nls.defaults.NATIVE_MAX_DOFS`.  A back-solve with the
factorisation kept (the mean of :data:`BACK_SOLVES`) prices a factorisation kept for a run:
the largest size at which PETSc's dearer first solve pays within :data:`PAYBACK_SOLVES`
back-solves sets :data:`dolfinx_friction.nls.defaults.KEPT_NATIVE_MAX_DOFS`.
"""
from __future__ import annotations

import argparse
import sys
import time

import _bench as B  # noqa: I001
import numpy as np

SOLVERS = {  # name: (pc_type, solver package, ordering)
    "MUMPS LU": ("lu", "mumps", None),
    "PETSc LU nd": ("lu", "petsc", "nd"),
    "PETSc LU rcm": ("lu", "petsc", "rcm"),
    "PETSc LU qmd": ("lu", "petsc", "qmd"),
    "UMFPACK LU": ("lu", "umfpack", None),
    "KLU": ("lu", "klu", None),
    "MUMPS LDL^T": ("cholesky", "mumps", None),
    "PETSc Cholesky nd": ("cholesky", "petsc", "nd"),
    "CHOLMOD": ("cholesky", "cholmod", None),
}
SIZES = {2: [6, 10, 16, 24, 36, 54, 80], 3: [2, 3, 4, 5, 6, 8, 10, 12]}
QUICK = {2: [10, 24], 3: [3, 6]}
#: back-solves timed (with the factorisation kept) per repeat
BACK_SOLVES = 20


def stiffness(gdim: int, n: int):
    """The held elastic stiffness on ``n`` cells per side (seqaij, free rows only)."""
    import dolfinx
    import dolfinx.fem.petsc
    import ufl
    from mpi4py import MPI
    from petsc4py import PETSc
    if gdim == 2:
        mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, n, n)
    else:
        mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_SELF, n, n, n,
                                             dolfinx.mesh.CellType.hexahedron)
    V = dolfinx.fem.VectorFunctionSpace(mesh, ("CG", 1))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    E, nu = 1000.0, 0.3
    mu_, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    eps = ufl.sym(ufl.grad(u))
    a = ufl.inner(2 * mu_ * eps + lam * ufl.tr(eps) * ufl.Identity(gdim),
                  ufl.sym(ufl.grad(v))) * ufl.dx
    A = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(a))
    A.assemble()

    def dofs(where) -> np.ndarray:
        nodes = dolfinx.mesh.locate_entities_boundary(mesh, 0, where)
        blocks = dolfinx.fem.locate_dofs_topological(V, 0, nodes)
        return (gdim * blocks[:, None] + np.arange(gdim)).ravel()
    held = dofs(lambda p: np.isclose(p[0], 0.0))
    top = dofs(lambda p: np.isclose(p[gdim - 1], 1.0))
    free = np.setdiff1d(np.arange(A.getSize()[0]), held).astype(PETSc.IntType)
    index = PETSc.IS().createGeneral(free, comm=PETSc.COMM_SELF)
    K = A.createSubMatrix(index, index)
    return K, np.searchsorted(free, np.intersect1d(top, free))


def unsymmetric(K, rows: np.ndarray, seed: int = 0):
    """``K`` with the values of ``rows`` scaled by 1 + 0.1 r (same pattern)."""
    from petsc4py import PETSc
    indptr, indices, values = K.getValuesCSR()
    values = values.copy()
    rng = np.random.default_rng(seed)
    for r in rows:
        values[indptr[r]:indptr[r + 1]] *= 1.0 + 0.1 * rng.random(indptr[r + 1] - indptr[r])
    return PETSc.Mat().createAIJ(K.getSize(), csr=(indptr, indices, values),
                                 comm=PETSc.COMM_SELF)


def time_solver(A, pc_type: str, package: str, ordering, repeats: int
                ) -> tuple[float, float, float]:
    """(first, repeated, back-solve) CPU seconds of a solve of ``A`` by a ``preonly`` KSP;
    back-solve: a solve with the factorisation kept (the mean of :data:`BACK_SOLVES`)."""
    from petsc4py import PETSc
    b = A.createVecLeft()
    b.setRandom()
    x = b.duplicate()
    r = b.duplicate()
    first, again, back = [], [], []
    for _ in range(repeats):
        M = A.copy()
        ksp = PETSc.KSP().create(PETSc.COMM_SELF)
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType(pc_type)
        pc.setFactorSolverType(package)
        if ordering:
            pc.setFactorOrdering(ordering)
        ksp.setOperators(M, M)
        t = time.process_time()
        ksp.solve(b, x)
        first.append(time.process_time() - t)
        check(M, b, x, r)
        M.scale(1.0 + 1e-3)
        t = time.process_time()
        ksp.solve(b, x)
        again.append(time.process_time() - t)
        check(M, b, x, r)
        t = time.process_time()
        for _ in range(BACK_SOLVES):
            ksp.solve(b, x)
        back.append((time.process_time() - t) / BACK_SOLVES)
        ksp.destroy()
        M.destroy()
    return min(first), min(again), min(back)


def check(A, b, x, r) -> None:
    A.mult(x, r)
    r.axpy(-1.0, b)
    assert r.norm() <= 1e-10 * b.norm(), r.norm() / b.norm()


def arguments(argv, doc: str) -> argparse.Namespace:
    """The options of this bench and of those on its matrices (bench_columns): ``--quick``,
    ``--repeats``, ``--no-results``; ``doc``: the script's docstring."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-results", action="store_true")
    return ap.parse_args(argv)


def main(argv=None) -> None:
    args = arguments(argv, __doc__)
    machine = B.machine()
    sizes = QUICK if args.quick else SIZES
    data = {}
    for gdim, ns in sizes.items():
        for n in ns:
            K, top = stiffness(gdim, n)
            cases = {"symmetric": K, "unsymmetric": unsymmetric(K, top)}
            dofs = K.getSize()[0]
            for case, A in cases.items():
                for name, (pc_type, package, ordering) in SOLVERS.items():
                    if case == "unsymmetric" and pc_type == "cholesky":
                        continue
                    first, again, back = time_solver(A, pc_type, package, ordering,
                                                     args.repeats)
                    data.setdefault((gdim, case, name), []).append((dofs, first, again,
                                                                    back))
                    print(f"{gdim}D", case, f"{dofs:,}", name, f"{1e3 * first:.2f}",
                          f"{1e3 * again:.2f}", f"{1e3 * back:.3f}", flush=True)
    report(data, sorted(sizes), machine, B.load_average(), args.repeats,
           args.no_results)


def pivot(data: dict) -> list[list]:
    """One row per (dimension, matrix, size), one column per solver."""
    keys = sorted({(g, c, d[0]) for (g, c, _), points in data.items() for d in points})
    rows = []
    for g, c, dofs in keys:
        row = [f"{g}D", c, f"{dofs:,}"]
        for name in SOLVERS:
            hit = [p for p in data.get((g, c, name), []) if p[0] == dofs]
            if not hit:
                row.append("-")
                continue
            _, first, again, _ = hit[0]
            row.append(f"{1e3 * again:.2f}" + (f" ({1e3 * first:.2f})"
                                               if name in ("MUMPS LU", "PETSc LU nd") else ""))
        rows.append(row)
    return rows


def payback(data: dict, gdim: int) -> tuple[list[list], int]:
    """The rows of the kept-factorisation table (symmetric stiffness, MUMPS LU against
    PETSc's LU nd: first solve, back-solve, the back-solves after which PETSc's dearer
    first solve has paid for itself) and the largest size where it pays within
    :data:`PAYBACK_SOLVES` back-solves."""
    mumps = data[(gdim, "symmetric", "MUMPS LU")]
    native = data[(gdim, "symmetric", "PETSc LU nd")]
    rows, largest = [], 0
    for m, p in zip(mumps, native):
        saved, extra = m[3] - p[3], p[1] - m[1]
        solves = 0.0 if extra <= 0.0 else (np.inf if saved <= 0.0 else extra / saved)
        if solves <= PAYBACK_SOLVES:
            largest = m[0]
        rows.append([f"{gdim}D", f"{m[0]:,}", f"{1e3 * m[1]:.2f}", f"{1e3 * p[1]:.2f}",
                     f"{1e3 * m[3]:.3f}", f"{1e3 * p[3]:.3f}",
                     "never" if solves == np.inf else f"{solves:.0f}"])
    return rows, largest


#: back-solves a run's kept factorisation is expected to serve (the Newton iterations of
#: the finite-strain comparisons in RESULTS.md: 45 to 130)
PAYBACK_SOLVES = 50


def report(data: dict, dims: list, machine: dict, load1: float, repeats: int,
           no_results: bool, note: str = "") -> None:
    """The chart, the table and the crossover (RESULTS.md section unless ``no_results``)."""
    crossover = {}
    for gdim in dims:
        mumps = data[(gdim, "unsymmetric", "MUMPS LU")]
        native = data[(gdim, "unsymmetric", "PETSc LU nd")]
        cheaper = [m[0] for m, p in zip(mumps, native) if p[2] <= m[2]]
        crossover[gdim] = max(cheaper) if cheaper else 0
    plt = B.pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.8))
    for ax, (gdim, case) in zip(axes, [(2, "unsymmetric"), (3, "unsymmetric"),
                                       (3, "symmetric")]):
        for (g, c, name), points in data.items():
            if (g, c) != (gdim, case) or (case == "symmetric" and "LU" in name
                                           and name != "MUMPS LU"):
                continue
            d = np.array(points)
            ax.loglog(d[:, 0], 1e3 * d[:, 2], "o-", label=name)
        ax.set_xlabel("dofs (free rows)")
        ax.set_ylabel("numeric factorisation + solve [ms CPU]")
        ax.set_title(f"{gdim}D, {case}")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    B.save_figure(fig, "factor_crossover.png",
                  "Direct solves of elastic stiffness matrices, repeated (numeric) solve",
                  machine)
    text = (f"`benchmarks/bench_factor.py`: {B.machine_line(machine, load1)}.\n\n"
            "A `preonly` direct solve of the held elastic stiffness (P1, unit square of "
            "triangles / unit cube of hexahedra; unsymmetric: the top face's rows scaled by "
            "1 + 0.1 r), serial, one thread; CPU milliseconds, least of "
            f"{repeats}: `first` (ordering, symbolic and numeric factorisation, "
            "back-solve), `again` (the same matrix, new values: numeric factorisation and "
            "back-solve, a Newton iteration's cost).  Every solve's relative residual "
            "<= 1e-10.  Chart: `figures/factor_crossover.png`.  `again` [ms] per solver "
            "(`first` of MUMPS LU and PETSc LU nd in brackets; - not timed):\n\n"
            + B.table(["dim", "matrix", "dofs", *SOLVERS], pivot(data))
            + "\n\nPETSc's LU (nd) costs no more than MUMPS's (repeated, unsymmetric) up to "
            + ", ".join(f"{crossover[g]:,} dofs in {g}D" for g in dims) + "." + note)
    kept = [payback(data, g) for g in dims]
    text += ("\n\nA factorisation kept for a whole run (the constant interior `K_II` of "
             "`nls/interior.py`: factorised once, back-solved at every Newton step): the "
             "symmetric stiffness's first solve and one back-solve [ms] (mean of "
             f"{BACK_SOLVES}), and the back-solves after which PETSc's dearer first solve "
             "has paid for itself (0: it is the cheaper one):\n\n"
             + B.table(["dim", "dofs", "MUMPS first", "PETSc nd first", "MUMPS back-solve",
                        "PETSc nd back-solve", "pays after"],
                       [r for rows, _ in kept for r in rows])
             + f"\n\nWithin {PAYBACK_SOLVES} back-solves PETSc's pays up to "
             + ", ".join(f"{largest:,} dofs in {g}D" for g, (_, largest) in zip(dims, kept))
             + ".")
    print(text)
    if not no_results:
        B.write_section("Direct solvers of small systems: MUMPS against PETSc's own", text)


if __name__ == "__main__":
    sys.exit(main())
