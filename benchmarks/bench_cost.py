"""Cost of a Newton iteration by phase on 3D frictional scenes, and the contact overhead.

    python benchmarks/bench_cost.py             # ~1.6e4 ... ~2.6e5 dofs (MUMPS), GAMG at 1.1e5 and 4.3e5
    python benchmarks/bench_cost.py --quick     # two small sizes (< 2 min)
    python benchmarks/bench_cost.py --sizes 6,8 --iterative-sizes 20 --no-results

Scene (``benchmarks/_meshes.two_boxes``, i.e. ``reference.meshes.two_boxes`` at resolution n):
an elastic block (2n x 2n x n hexahedra, Q4 slave faces) on a foundation (m x m x n, m ~ 3n,
master), E = 1000, nu = 0.3 for both, linear law with CalculiX's K = 50 E and
lambda = E/2 (``"calculix"``), mu = 0.3; step 1 presses the block top down by 0.005
(1 increment), step 2 slides it by 0.02 along x (2 increments, full slip), foundation
bottom fixed; ``[solver] linear = "direct"`` (MUMPS at every size).  Serial.

Each configuration runs in its own process (clean peak memory, nothing left in PETSc's
options database):

* ``contact`` -- the scene as above, MUMPS LU every iteration (the default);
* ``reuse`` -- the same with ``reuse_factorisation=True``;
* ``no contact`` -- the same mesh, bcs and steps with the contact pair removed (two
  independent linear bodies: 1 Newton iteration per increment);
* beyond the sizes MUMPS handles here, ``contact`` and ``no contact`` with
  ``petsc_options = {ksp_type: gmres, pc_type: gamg, ksp_rtol: 1e-10, ksp_max_it: 1000,
  ksp_gmres_restart: 200}`` (PETSc's GAMG defaults otherwise; the Jacobian carries the block
  size and the rigid-body modes as near null space).

Reported per iteration (phase seconds / Newton iterations = linear solves): contact search,
contact assembly (element evaluation, residual and Jacobian fill), bulk assembly (K u),
linear solve; set-up separately.  Phase times are CPU seconds of the single-threaded
process (the machine is shared; wall times are listed too).  The contact overhead is
(time per iteration with contact) / (time per iteration without), both at the same size.
Chart: ``benchmarks/figures/cost_per_iteration.png`` (log-log).

Target: contact overhead <= 1.3.

Why the pattern holds all 16 candidate faces of a slave node (measured once, n = 8, 35k
dofs, PORD): the factorisation takes 1.49x the flops of the two separate bodies with the
candidate pattern and 1.32x when each slave node is coupled to one face only; most of the
cost is joining the bodies, and the candidate pattern spares a new matrix and a new MUMPS
analysis at every re-pairing.  MUMPS's other orderings are worse here: AMF 1.75x, AMD and
QAMD 2.7x the flops of PORD.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import _bench as B  # noqa: I001
import _meshes as M

E, NU, MU = 1000.0, 0.3, 0.3
PRESS, SLIDE = 0.005, 0.02
PHASES = ("contact_search", "contact_assembly", "bulk_assembly", "linear_solve")
GAMG = {"ksp_type": "gmres", "pc_type": "gamg", "ksp_rtol": 1e-10, "ksp_atol": 0.0,
        "ksp_max_it": 1000, "ksp_gmres_restart": 200}

FULL_SIZES, FULL_REUSE, FULL_ITERATIVE = (6, 8, 10, 12, 16, 18), (6, 8, 10, 12), (12, 20)
QUICK_SIZES, QUICK_REUSE, QUICK_ITERATIVE = (4, 6), (4,), ()


def two_boxes_mesh(n: int) -> Path:
    """The two_boxes mesh at resolution n in the work directory, built if missing."""
    path = B.work_dir("boxes") / f"two_boxes_n{n}.msh"
    if not path.exists():
        M.two_boxes(path, n)
    return path


def scene(n: int, contact: bool = True, slide_increments: int = 2, mu: float = MU):
    """The block on a foundation at resolution ``n`` (module docstring); ``mu = 0``:
    frictionless."""
    from dolfinx_friction.scene.model import (BC, Body, ContactPair, Output, Scene,
                                              SolverSettings, Step)
    return Scene(
        mesh=two_boxes_mesh(n), bodies=(Body("block", E, NU), Body("foundation", E, NU)),
        contacts=(ContactPair("block_bottom", "foundation_top", mu=mu, K="calculix",
                              stick_slope="calculix"),) if contact else (),
        steps=(Step("press", increments=1, bcs=(BC("foundation_bottom", (0.0, 0.0, 0.0)),
                                                BC("block_top", (0.0, 0.0, -PRESS)))),
               Step("slide", increments=slide_increments,
                    bcs=(BC("block_top", (SLIDE, 0.0, -PRESS)),))),
        output=Output(fields=False, contact_table=False,
                      reactions=("block_top", "foundation_bottom")),
        solver=SolverSettings("direct"))  # MUMPS unless the run is given GAMG's options


def worker(args: list[str]) -> None:
    if args[0] == "factor":
        return B.emit(factor_stats(int(args[1]), args[2] == "1"))
    n, contact, reuse, solver = int(args[0]), args[1] == "1", args[2] == "1", args[3]
    profile = len(args) > 4 and args[4] == "profile"
    kwargs = {"reuse_factorisation": reuse}
    if solver == "gamg":
        kwargs["petsc_options"] = dict(GAMG)
    if profile:
        (result, num), rows = B.profile_call(lambda: B.timed_run(scene(n, contact), **kwargs),
                                             top=16)
        num["profile"] = rows
    else:
        result, num = B.timed_run(scene(n, contact), **kwargs)
    num.update(n=n, contact=contact, reuse=reuse, solver=solver,
               reactions=[inc.reactions["block_top"].tolist() for inc in result.increments])
    B.emit(num)


def factor_stats(n: int, contact: bool) -> dict:
    """Matrix and MUMPS factor sizes after the press increment (one process per call)."""
    result, num = B.timed_run(scene(n, contact), max_increments=1)
    s = result.solver
    F = s.linear.ksp.getPC().getFactorMatrix()
    return {"n": n, "contact": contact, "dofs": num["dofs"],
            "nnz": int(result.problem.system.matrix().getInfo()["nz_used"]),
            "factor_entries": int(F.getMumpsInfog(20)),
            "flops": float(F.getMumpsRinfog(3)), "ordering": int(F.getMumpsInfog(7)),
            "solve_per_it": num["phases"]["linear_solve"] / max(num["newton"], 1)}


def factor_table(stats: list[dict]) -> str:
    rows = []
    for c, o in _factor_pairs(stats):
        rows.append([f"{c['dofs']:,}", f"{o['nnz']:,} -> {c['nnz']:,} ({c['nnz'] / o['nnz']:.2f}x)",
                     f"{o['factor_entries']:,} -> {c['factor_entries']:,} "
                     f"({c['factor_entries'] / o['factor_entries']:.2f}x)",
                     f"{o['flops']:.3g} -> {c['flops']:.3g} ({c['flops'] / o['flops']:.2f}x)",
                     f"{c['solve_per_it'] / o['solve_per_it']:.2f}x"])
    nnz = max(c["nnz"] / o["nnz"] for c, o in _factor_pairs(stats))
    flops = [c["flops"] / o["flops"] for c, o in _factor_pairs(stats)]
    return ("Why the solve costs more with contact (MUMPS, after the press increment; ordering "
            f"INFOG(7) = {stats[0]['ordering']}, i.e. PORD: this MUMPS has no METIS/SCOTCH):\n\n"
            + B.table(["dofs", "matrix non-zeros: no contact -> contact",
                       "factor entries INFOG(20)", "factorisation flops RINFOG(3)",
                       "solve time ratio"], rows)
            + f"\n\nThe contact couplings add at most {100 * (nnz - 1):.0f} % non-zeros, but "
            f"the factorisation takes {min(flops):.2f}-{max(flops):.2f}x the flops: without "
            "contact the block and the foundation are two independent systems, which LU "
            "factorises separately; the couplings join them into one.")


def _factor_pairs(stats: list[dict]) -> list[tuple[dict, dict]]:
    return [(next(s for s in stats if s["n"] == n and s["contact"]),
             next(s for s in stats if s["n"] == n and not s["contact"]))
            for n in sorted({s["n"] for s in stats})]


def per_iteration(r: dict) -> dict:
    its = max(r["newton"], 1)
    out = {p: r["phases"][p] / its for p in PHASES}
    out["total"] = sum(out.values())
    return out


def chart(rows: list[dict], machine: dict) -> Path:
    plt = B.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.2), dpi=100)
    ax = axes[0]
    colours = {"contact_search": "#9467bd", "contact_assembly": "#d62728",
               "bulk_assembly": "#2ca02c", "linear_solve": "#1f77b4", "total": "k"}
    for solver, ls in (("mumps", "-"), ("gamg", ":")):
        sel = sorted((r for r in rows if r["ok"] and r["contact"] and not r["reuse"]
                      and r["solver"] == solver), key=lambda r: r["dofs"])
        if not sel:
            continue
        x = [r["dofs"] for r in sel]
        for key, c in colours.items():
            ax.loglog(x, [per_iteration(r)[key] for r in sel], ls=ls, marker="o", color=c,
                      label=f"{key.replace('_', ' ')} ({solver})")
        nc = sorted((r for r in rows if r["ok"] and not r["contact"] and r["solver"] == solver),
                    key=lambda r: r["dofs"])
        if nc:
            ax.loglog([r["dofs"] for r in nc], [per_iteration(r)["total"] for r in nc], ls=ls,
                      marker="x", color="grey", label=f"total without contact ({solver})")
    ax.set_xlabel("dofs")
    ax.set_ylabel("CPU seconds per Newton iteration")
    ax.set_title("time per Newton iteration by phase", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    ax = axes[1]
    for solver, marker in (("mumps", "o"), ("gamg", "s")):
        pts = []
        for r in rows:
            if not (r["ok"] and r["contact"] and not r["reuse"] and r["solver"] == solver):
                continue
            base = _match(rows, r["n"], contact=False, solver=solver)
            if base:
                pts.append((r["dofs"], per_iteration(r)["total"] / per_iteration(base)["total"]))
        if pts:
            pts.sort()
            ax.semilogx(*zip(*pts), marker=marker, label=f"contact overhead ({solver})")
    kept = sorted((r["dofs"], per_iteration(r)["total"]
                   / per_iteration(_match(rows, r["n"], False, "mumps"))["total"])
                  for r in rows if r["ok"] and r["reuse"] and _match(rows, r["n"], False, "mumps"))
    if kept:
        ax.semilogx(*zip(*kept), marker="D", label="contact overhead (mumps, kept factorisation)")
    reuse_pts = []
    for r in rows:
        if r["ok"] and r["reuse"]:
            base = _match(rows, r["n"], contact=True, solver="mumps", reuse=False)
            if base:
                reuse_pts.append((r["dofs"], r["cpu"] / base["cpu"]))
    if reuse_pts:
        reuse_pts.sort()
        ax.semilogx(*zip(*reuse_pts), marker="^", label="run time reuse / no reuse")
    ax.axhline(1.3, color="grey", ls=":", label="target overhead 1.3")
    ax.axhline(1.0, color="k", lw=0.6)
    ax.set_xlabel("dofs")
    ax.set_ylabel("ratio")
    ax.set_title("contact overhead per iteration; reuse_factorisation", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    return B.save_figure(fig, "cost_per_iteration.png", "two_boxes, mu = 0.3, serial; CPU time",
                         machine)


def _match(rows, n, contact, solver, reuse=False):
    for r in rows:
        if (r["ok"] and r["n"] == n and r["contact"] == contact and r["solver"] == solver
                and r["reuse"] == reuse):
            return r
    return None


def report(rows, machine, load_end, quick, figure) -> str:
    out = [
        "`benchmarks/bench_cost.py`" + (" --quick" if quick else "") + ": block on a "
        "foundation (`reference.meshes.two_boxes` via `benchmarks/_meshes.py`, hexahedra, Q4 "
        f"faces), E = {E:g}, nu = {NU}, K = 50 E, mu = {MU}; press {PRESS} (1 increment), "
        f"slide {SLIDE} (2 increments, full slip); serial; each configuration in its own "
        "process.",
        "",
        f"* {B.machine_line(machine, load_end)}",
        "* seconds are CPU seconds of the single-threaded process (phase timers read "
        "`time.process_time`); per iteration = phase total / Newton iterations (= linear "
        "solves; the assemblies include the final residual check of each increment).",
        "* 'no contact' = same mesh, bcs and steps without the contact pair (each body linear: "
        "1 iteration per increment).  Overhead = per-iteration total with / without contact.",
        "",
    ]
    table_rows = []
    for r in sorted(rows, key=lambda r: (r["solver"] != "mumps", r["n"], not r["contact"],
                                         r["reuse"])):
        label = ("contact" if r["contact"] else "no contact") + (" + reuse" if r["reuse"] else "")
        if not r["ok"]:
            table_rows.append([r["n"], "-", label, r["solver"]] + ["-"] * 11
                              + [r["error"][:80]])
            continue
        pi = per_iteration(r)
        base = _match(rows, r["n"], False, r["solver"]) if r["contact"] else None
        overhead = f"{pi['total'] / per_iteration(base)['total']:.2f}" if base else ""
        table_rows.append([
            r["n"], f"{r['dofs']:,}", label, r["solver"], r["newton"],
            f"{pi['contact_search']:.3g}", f"{pi['contact_assembly']:.3g}",
            f"{pi['bulk_assembly']:.3g}", f"{pi['linear_solve']:.3g}", f"{pi['total']:.3g}",
            overhead, B.fmt_s(r["phases"]["setup"]), B.fmt_s(r["cpu"]), B.fmt_s(r["wall"]),
            f"{r['rss_mib']:.0f}", f"{r['load'][0]:.1f}"])
    out.append(B.table(["n", "dofs", "run", "solver", "Newton its", "search/it",
                        "contact asm/it", "bulk asm/it", "solve/it", "total/it", "overhead",
                        "setup", "CPU total", "wall total", "peak RSS [MiB]", "load"],
                       table_rows, "lrllrrrrrrrrrrrr"))
    out.append("")
    ov = []
    for r in rows:
        if r["ok"] and r["contact"] and not r["reuse"]:
            base = _match(rows, r["n"], False, r["solver"])
            if base:
                ov.append((r["dofs"], r["solver"],
                           per_iteration(r)["total"] / per_iteration(base)["total"],
                           per_iteration(r)["linear_solve"] / per_iteration(base)["linear_solve"]))
    if ov:
        worst = max(ov, key=lambda t: t[2])
        out.append("Target: contact overhead <= 1.3.  Measured: " + ", ".join(
            f"{d:,} dofs ({s}) {o:.2f} (solve alone {so:.2f})" for d, s, o, so in sorted(ov))
            + (" -- **met**." if worst[2] <= 1.3 else f" -- **missed** (worst {worst[2]:.2f})."))
        kept = [(r["dofs"], per_iteration(r)["total"]
                 / per_iteration(_match(rows, r["n"], False, "mumps"))["total"])
                for r in rows if r["ok"] and r["reuse"] and _match(rows, r["n"], False, "mumps")]
        if kept:
            out.append("With the kept factorisation (`reuse_factorisation=True`, the default "
                       "for MUMPS where it pays), against the same no-contact runs: " + ", ".join(
                           f"{d:,} dofs {o:.2f}" for d, o in sorted(kept)) + ".")
        out.append("")
    reuse = []
    for r in rows:
        if r["ok"] and r["reuse"]:
            base = _match(rows, r["n"], True, "mumps")
            if base:
                reuse.append(f"{r['dofs']:,} dofs: {r['cpu']:.3g} s vs {base['cpu']:.3g} s "
                             f"({r['cpu'] / base['cpu']:.2f}x), solve/it "
                             f"{per_iteration(r)['linear_solve']:.3g} vs "
                             f"{per_iteration(base)['linear_solve']:.3g} s, Newton its "
                             f"{r['newton']} vs {base['newton']}")
    if reuse:
        out.append("`reuse_factorisation=True` vs False (whole run, CPU): " + "; ".join(reuse)
                   + ".")
        out.append("")
    out.append(f"Chart: `benchmarks/figures/{figure.name}`.")
    return "\n".join(out)


def main(argv=None) -> None:
    ap = B.worker_parser(__doc__)
    ap.add_argument("--sizes", help="two_boxes resolutions n for MUMPS (comma separated)")
    ap.add_argument("--reuse-sizes")
    ap.add_argument("--iterative-sizes")
    ap.add_argument("--json", help="also write all rows to this file")
    ap.add_argument("--factor-stats", help="sizes n (comma separated) at which to measure the "
                                           "matrix and factor size with and without contact "
                                           "(default: the MUMPS sizes up to 12; '' for none)")
    ap.add_argument("--from-json", help="no runs: report the rows of this --json file "
                                        "(and its profile, if the run got that far)")
    ap.add_argument("--profile", type=int, metavar="N",
                    help="also profile (cProfile) the contact run at resolution N (default: the "
                         "largest MUMPS size up to 12; 0: no profile)")
    args = ap.parse_args(argv)
    if args.worker:
        return worker(args.worker)
    if args.from_json:
        data = json.loads(Path(args.from_json).read_text())
        if isinstance(data, list):
            data = {"rows": data}
        rows, prof, machine = data["rows"], data.get("profile"), data.get("machine", B.machine())
        figure = chart(rows, machine)
        text = report(rows, machine, data.get("load_end", B.load_average()), False, figure)
        if data.get("factor_stats"):
            text += "\n\n" + factor_table(data["factor_stats"])
        if prof:
            text += "\n\n" + B.profile_table(prof["profile"], prof["label"])
        print(text)
        if not args.no_results:
            B.write_section("Cost per Newton iteration and contact overhead (3D, frictional)",
                            text)
        return
    ints = lambda s, d: tuple(int(x) for x in s.split(",") if x) if s is not None else d  # noqa
    sizes = ints(args.sizes, QUICK_SIZES if args.quick else FULL_SIZES)
    reuse = ints(args.reuse_sizes, QUICK_REUSE if args.quick else FULL_REUSE)
    iterative = ints(args.iterative_sizes, QUICK_ITERATIVE if args.quick else FULL_ITERATIVE)
    machine = B.machine()
    plan = []
    for n in sizes:
        plan += [(n, True, False, "mumps"), (n, False, False, "mumps")]
        if n in reuse:
            plan.append((n, True, True, "mumps"))
    for n in iterative:
        plan += [(n, True, False, "gamg"), (n, False, False, "gamg")]
    rows = []
    for n, contact, reuse_, solver in plan:
        two_boxes_mesh(n)  # built once, here, not concurrently by workers
        row = {"n": n, "contact": contact, "reuse": reuse_, "solver": solver}
        try:
            row.update(B.run_worker(Path(__file__), [str(n), str(int(contact)),
                                                     str(int(reuse_)), solver]))
            row["ok"] = True
            pi = per_iteration(row)
            print(f"n={n:2d} dofs={row['dofs']:7d} contact={contact!s:5} reuse={reuse_!s:5} "
                  f"{solver}: its={row['newton']:3d} per it: search {pi['contact_search']:.3f} "
                  f"contact {pi['contact_assembly']:.3f} bulk {pi['bulk_assembly']:.4f} solve "
                  f"{pi['linear_solve']:.3f} total {pi['total']:.3f} s; setup "
                  f"{row['phases']['setup']:.1f} s; cpu {row['cpu']:.1f} s wall "
                  f"{row['wall']:.1f} s rss {row['rss_mib']:.0f} MiB load {row['load'][0]:.1f}",
                  flush=True)
        except Exception as e:  # noqa: BLE001
            row.update(ok=False, error=str(e).splitlines()[-1][:200])
            print(f"n={n} contact={contact} reuse={reuse_} {solver}: FAILED {e}", flush=True)
        rows.append(row)
        if args.json:
            Path(args.json).write_text(json.dumps(rows, indent=1))
    fsizes = ints(args.factor_stats, tuple(n for n in sizes if n <= 12))
    fstats = [B.run_worker(Path(__file__), ["factor", str(n), str(int(c))])
              for n in fsizes for c in (True, False)]
    prof_n = args.profile if args.profile is not None else (0 if args.quick else max(
        [n for n in sizes if n <= 12], default=0))
    prof = None
    if prof_n:
        prof = B.run_worker(Path(__file__), [str(prof_n), "1", "0", "mumps", "profile"])
        print(B.profile_table(prof["profile"]))
    figure = chart(rows, machine)
    print(f"chart: {figure}")
    text = report(rows, machine, B.load_average(), args.quick, figure)
    if fstats:
        text += "\n\n" + factor_table(fstats)
        print(factor_table(fstats))
    if prof:
        prof["label"] = (f"Profile of the contact run at n = {prof_n} ({prof['dofs']:,} dofs, "
                         f"{prof['newton']} Newton iterations), ")
        text += "\n\n" + B.profile_table(prof["profile"], prof["label"])
    if args.json:
        Path(args.json).write_text(json.dumps({"rows": rows, "profile": prof, "machine": machine,
                                               "load_end": B.load_average(),
                                               "factor_stats": fstats}, indent=1))
    print(text)
    if not args.no_results:
        B.write_section("Cost per Newton iteration and contact overhead (3D, frictional)", text)


if __name__ == "__main__":
    sys.exit(main())
