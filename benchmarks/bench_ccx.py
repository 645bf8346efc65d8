"""Side by side with CalculiX: the same scene, timed in the same run, at three sizes.

    python benchmarks/bench_ccx.py              # n = 6, 8, 10: ~1.6e4, ~3.5e4, ~6.7e4 dofs
    python benchmarks/bench_ccx.py --quick      # n = 3, 4, 5 (< 2 min)
    python benchmarks/bench_ccx.py --sizes 6,10 --no-results

The scene of ``bench_cost.py`` (block on a foundation, structured first-order hexahedra,
E = 1000, nu = 0.3, linear law K = 50 E, sigma_inf = E/70000, c0 = 1e-3, mu = 0.3,
lambda = E/2; press 0.005 in 1 increment, slide 0.02 in 2 increments).  The very same
:class:`~dolfinx_friction.model.Scene` object is solved by dolfinx_friction (serial, MUMPS,
exact tangent, tolerance 1e-9 r0) and written by :func:`dolfinx_friction.calculix.write_inp`
for ``ccx`` (same mesh, nodes, laws, parameters, increments; the deck's default tightened
``*CONTROLS``), which runs single-threaded (``OMP_NUM_THREADS=1``) -- one core each.

Measured per size, alternately in this one process: wall and CPU time of ``ccx`` (CPU from
``getrusage(RUSAGE_CHILDREN)``) and of our ``run()`` (CPU of this process), the time spent
writing the deck, iterations, and the reactions on the pushed top and the fixed bottom in every
increment: ``|R - R_ccx| / |R_ccx|``.

Target: at >= 30k dofs, our total wall time <= 0.5 x CalculiX's.  Because the machine is
shared, the ratio is given for wall and for CPU time; the CPU ratio is the one that does not
depend on the other jobs.
"""
from __future__ import annotations

import argparse
import json
import re
import sys
import time
from pathlib import Path

import _bench as B  # noqa: I001
import numpy as np

import bench_cost as C

FULL, QUICK = (6, 8, 10), (3, 4, 5)
GROUPS = ("block_top", "foundation_bottom")


def ccx_iterations(log: str) -> tuple[int, int]:
    """(increments, factorisations) from the ccx log."""
    incs = len(re.findall(r"^\s*increment \d+ attempt", log, re.M))
    facs = len(re.findall(r"Factoring the system of equations", log))
    return incs, facs


def one_size(n: int) -> dict:
    from dolfinx_friction import calculix
    scene = C.scene(n)
    row = {"n": n}
    # ---- CalculiX
    inp = B.work_dir("ccx") / f"boxes_n{n}.inp"
    t0 = time.perf_counter()
    calculix.write_inp(scene, inp)
    row["write_inp"] = time.perf_counter() - t0
    load0 = B.load_average()
    c0 = B.children_cpu()
    ccx = calculix.run_ccx(inp, details=True, threads=1, timeout=7200)
    row.update(ccx_cpu=B.children_cpu() - c0, ccx_wall=ccx.wall, ccx_load=[load0,
                                                                          B.load_average()])
    row["ccx_increments"], row["ccx_solves"] = ccx_iterations(ccx.log)
    # ---- dolfinx_friction
    result, num = B.timed_run(scene)
    row.update(ours=num)
    # ---- reactions, increment by increment
    diffs = []
    for inc in result.increments:
        theirs = ccx.reactions.get(inc.step, {}).get(inc.increment)
        if theirs is None:
            diffs.append({"step": inc.step, "increment": inc.increment, "missing": True})
            continue
        for g in GROUPS:
            ours, ref = np.asarray(inc.reactions[g]), np.asarray(theirs[g])
            diffs.append({"step": inc.step, "increment": inc.increment, "group": g,
                          "ours": ours.tolist(), "ccx": ref.tolist(),
                          "rel": float(np.linalg.norm(ours - ref) / np.linalg.norm(ref)),
                          "rel_x": (float(abs(ours[0] - ref[0]) / abs(ref[0]))
                                    if abs(ref[0]) > 1e-6 * np.linalg.norm(ref) else None),
                          "rel_z": float(abs(ours[2] - ref[2]) / abs(ref[2]))})
    row["diffs"] = diffs
    row["worst"] = max((d["rel"] for d in diffs if "rel" in d), default=float("nan"))
    return row


def chart(rows, machine) -> Path:
    plt = B.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.6), dpi=100)
    x = [r["ours"]["dofs"] for r in rows]
    ax = axes[0]
    ax.loglog(x, [r["ccx_cpu"] for r in rows], "s-", color="#d62728", label="CalculiX CPU")
    ax.loglog(x, [r["ours"]["cpu"] for r in rows], "o-", color="#1f77b4",
              label="dolfinx_friction CPU")
    ax.loglog(x, [r["ccx_wall"] for r in rows], "s:", color="#d62728", alpha=0.5,
              label="CalculiX wall")
    ax.loglog(x, [r["ours"]["wall"] for r in rows], "o:", color="#1f77b4", alpha=0.5,
              label="dolfinx_friction wall")
    ax.set_xlabel("dofs")
    ax.set_ylabel("seconds (whole analysis)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    ax = axes[1]
    ax.semilogx(x, [r["ours"]["cpu"] / r["ccx_cpu"] for r in rows], "o-", label="CPU ratio")
    ax.semilogx(x, [r["ours"]["wall"] / r["ccx_wall"] for r in rows], "s--", label="wall ratio")
    ax.axhline(0.5, color="grey", ls=":", label="target 0.5")
    ax.axhline(1.0, color="k", lw=0.6)
    ax.set_xlabel("dofs")
    ax.set_ylabel("dolfinx_friction / CalculiX")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.suptitle(f"two_boxes, mu = 0.3, 3 increments, one core each (load {machine['load'][0]:.1f} "
                 f"on {machine['nproc']} cores)", fontsize=10)
    fig.tight_layout()
    path = B.FIGURES / "ccx_comparison.png"
    fig.savefig(path)
    plt.close(fig)
    return path


def report(rows, machine, load_end, quick, figure) -> str:
    from dolfinx_friction import calculix
    out = [
        "`benchmarks/bench_ccx.py`" + (" --quick" if quick else "") + ": the scene of "
        "`bench_cost.py` (block on a foundation, C3D8 / Q4 faces, K = 50 E, mu = 0.3, press 1 + "
        "slide 2 increments), one `Scene` object solved by dolfinx_friction and written by "
        f"`calculix.write_inp` for `{calculix.ccx_executable()}` (single-threaded, SPOOLES as "
        "the deck's solver log says); both in the same process run, one after the other, per "
        "size.",
        "",
        f"* {B.machine_line(machine, load_end)}",
        "* ours = the whole `run()` (mesh reading, set-up, Newton, reactions); ccx = the whole "
        "`ccx` process (deck writing, listed separately, excluded).  CPU: our process / the ccx "
        "child (`RUSAGE_CHILDREN`).",
        "",
    ]
    trs = []
    for r in rows:
        o = r["ours"]
        trs.append([r["n"], f"{o['dofs']:,}", f"{o['newton']} / {o['increments']}",
                    f"{r['ccx_solves']} / {r['ccx_increments']}",
                    B.fmt_s(o["cpu"]), B.fmt_s(r["ccx_cpu"]), f"{o['cpu'] / r['ccx_cpu']:.2f}",
                    B.fmt_s(o["wall"]), B.fmt_s(r["ccx_wall"]),
                    f"{o['wall'] / r['ccx_wall']:.2f}", f"{r['write_inp']:.2f}",
                    f"{100 * r['worst']:.3f}", f"{r['ccx_load'][0]:.1f} / {o['load'][0]:.1f}"])
    out.append(B.table(["n", "dofs", "our solves / incs", "ccx solves / incs", "our CPU [s]",
                        "ccx CPU [s]", "CPU ratio", "our wall [s]", "ccx wall [s]",
                        "wall ratio", "write_inp [s]", "max dR/R [%]", "load ccx / ours"],
                       trs))
    out.append("")
    out.append("Reactions, every increment (block top; the foundation bottom is its mirror):")
    out.append("")
    drs = []
    for r in rows:
        for d in r["diffs"]:
            if d.get("group") != "block_top":
                continue
            drs.append([r["ours"]["dofs"], d["step"], d["increment"],
                        "[" + ", ".join(f"{v:.5g}" for v in d["ours"]) + "]",
                        "[" + ", ".join(f"{v:.5g}" for v in d["ccx"]) + "]",
                        f"{100 * d['rel']:.3f}",
                        "-" if d["rel_x"] is None else f"{100 * d['rel_x']:.3f}",
                        f"{100 * d['rel_z']:.3f}"])
    out.append(B.table(["dofs", "step", "inc", "R ours", "R ccx", "|dR|/|R| [%]", "dRx/Rx [%]",
                        "dRz/Rz [%]"], drs, "rrrllrrr"))
    out.append("")
    big = [r for r in rows if r["ours"]["dofs"] >= 30000]
    if big:
        w = max(r["ours"]["wall"] / r["ccx_wall"] for r in big)
        c = max(r["ours"]["cpu"] / r["ccx_cpu"] for r in big)
        out.append(f"Target: at >= 30k dofs, total wall time <= 0.5 x CalculiX's.  Measured "
                   f"(worst over the sizes >= 30k): wall ratio {w:.2f}, CPU ratio {c:.2f} -- "
                   + ("**met**." if c <= 0.5 else "**missed** (CPU ratio, the load-independent "
                                                  "one)."))
    else:
        out.append("Target (>= 30k dofs, wall <= 0.5 x CalculiX): no size >= 30k dofs in this run.")
    out.append("")
    out.append(f"Chart: `benchmarks/figures/{figure.name}`.")
    return "\n".join(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--sizes")
    ap.add_argument("--no-results", action="store_true")
    ap.add_argument("--json", help="also write the measured rows to this file")
    args = ap.parse_args(argv)
    from dolfinx_friction import calculix
    if not calculix.ccx_available():
        print("ccx not found (Debian: apt-get install calculix-ccx, or set $CCX)")
        return 1
    sizes = (tuple(int(x) for x in args.sizes.split(",")) if args.sizes
             else QUICK if args.quick else FULL)
    machine = B.machine()
    # warm-up (untimed): form compilation and imports of our side
    B.timed_run(C.scene(2))
    rows = []
    for n in sizes:
        r = one_size(n)
        rows.append(r)
        o = r["ours"]
        print(f"n={n} dofs={o['dofs']}: ours {o['newton']} solves cpu {o['cpu']:.1f} s wall "
              f"{o['wall']:.1f} s | ccx {r['ccx_solves']} solves cpu {r['ccx_cpu']:.1f} s wall "
              f"{r['ccx_wall']:.1f} s | ratio cpu {o['cpu'] / r['ccx_cpu']:.2f} wall "
              f"{o['wall'] / r['ccx_wall']:.2f} | max dR/R {100 * r['worst']:.3f} % | load "
              f"{B.load_average():.1f}", flush=True)
        if args.json:
            Path(args.json).write_text(json.dumps(rows, indent=1))
    figure = chart(rows, machine)
    text = report(rows, machine, B.load_average(), args.quick, figure)
    print(text)
    if not args.no_results:
        B.write_section("Side by side with CalculiX", text)


if __name__ == "__main__":
    sys.exit(main())
