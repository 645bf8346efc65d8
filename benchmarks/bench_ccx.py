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
    return {"n": n, **compare(C.scene(n), GROUPS, f"boxes_n{n}")}


def compare(scene, groups, label: str) -> dict:
    """Both codes on ``scene``: times, iterations and every increment's reactions of
    ``groups`` (``|R - R_ccx| / |R_ccx|``)."""
    from dolfinx_friction import calculix
    row = {"case": label}
    # ---- CalculiX
    inp = B.work_dir("ccx") / f"{label}.inp"
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
        # ccx runs fixed increments: its k-th ends at k / N of the step; ours may have cut
        # back (then its numbers run ahead): compare at the same pseudo-time
        n = scene.steps[inc.step].increments
        k = round((inc.t - inc.step) * n)
        theirs = (ccx.reactions.get(inc.step, {}).get(k)
                  if abs((inc.t - inc.step) * n - k) < 1e-9 else None)
        if theirs is None:
            diffs.append({"step": inc.step, "increment": inc.increment, "missing": True})
            continue
        for g in groups:
            ours, ref = np.asarray(inc.reactions[g]), np.asarray(theirs[g])
            big = np.abs(ref) > 1e-6 * np.linalg.norm(ref)
            diffs.append({"step": inc.step, "increment": inc.increment, "group": g,
                          "ours": ours.tolist(), "ccx": ref.tolist(),
                          "rel": float(np.linalg.norm(ours - ref) / np.linalg.norm(ref)),
                          "rel_x": (float(abs(ours[0] - ref[0]) / abs(ref[0]))
                                    if big[0] else None),
                          "rel_z": float(abs(ours[-1] - ref[-1]) / abs(ref[-1]))
                          if big[-1] else None})
    row["diffs"] = diffs
    row["worst"] = max((d["rel"] for d in diffs if "rel" in d), default=float("nan"))
    row["reactions"] = [{g: list(map(float, inc.reactions[g])) for g in groups}
                        for inc in result.increments]
    return row


# ----------------------------------------------------------------------------- kinds
#: Hertz cylinder on a block (demos/hertz_cylinder.py's geometry and mesh), one layer thick
HERTZ_K, HERTZ_INCREMENTS, HERTZ_PRESS, LAYER = 1.0e7, 10, 0.25, 0.1
HERTZ_SIZES, HERTZ_QUICK = (0.08, 0.05, 0.04), (0.08,)
IRONING_SIZES, IRONING_QUICK = ((20.0, 120, 24, 40),), ((10.0, 40, 6, 32),)
HERTZ_GROUPS, IRONING_GROUPS = ("cylinder_top", "block_bottom"), ("die_top", "block_bottom")


def hertz_scene(h: float, three_d: bool):
    """The Hertz line contact of ``demos/hertz_cylinder.py`` (quarter model, contact-zone
    element size ``h``), K = 1e7, frictionless, pressed 0.25 in 10 increments: in 2D
    (quadrilaterals, plane strain) or as its twin of one layer of hexahedra (the same
    quadrilaterals extruded by ``LAYER``, ``u_z = 0`` on both faces)."""
    import _meshes as M
    from dolfinx_friction.model import BC, Body, ContactPair, Output, Scene, Step
    two = B.work_dir("ccx") / f"hertz_h{h}_2d.msh"
    if not two.exists():
        B.demo_module("hertz_cylinder").build_mesh(two, h_contact=h)
    mesh = two
    if three_d:
        mesh = two.with_name(f"hertz_h{h}_3d.msh")
        if not mesh.exists():
            M.one_layer(two, mesh, LAYER)

    def u(*c):
        return c + (None,) if three_d else c

    bcs = (BC("block_bottom", u(0.0, 0.0)), BC("block_symmetry", u(0.0, None)),
           BC("cylinder_symmetry", u(0.0, None)), BC("cylinder_top", u(0.0, -HERTZ_PRESS)))
    if three_d:
        bcs += (BC("block_faces", (None, None, 0.0)), BC("cylinder_faces", (None, None, 0.0)))
    return Scene(mesh=mesh, bodies=(Body("cylinder", 1000.0, 0.3), Body("block", 1000.0, 0.3)),
                 contacts=(ContactPair("cylinder_surface", "block_top", K=HERTZ_K),),
                 steps=(Step("press", increments=HERTZ_INCREMENTS, bcs=bcs),),
                 output=Output(fields=False, contact_table=False, reactions=HERTZ_GROUPS))


def ironing_scene(size):
    """The one-layer plane-strain ironing of tests/verification/test_calculix_nlgeom.py,
    linear bodies, mu = 0.3, pressed in 10 and dragged in 40 increments."""
    from tests.verification import test_calculix_nlgeom as T
    length, nx, ny, n_arc = size
    path = B.work_dir("ccx") / f"ironing_{nx}x{ny}.msh"
    if not path.exists():
        T.ironing_mesh(path, length=length, nx=nx, ny=ny, bias=0.9 if ny > 6 else 0.75,
                       n_arc=n_arc)
    return T.ironing_scene(path, "linear", press_increments=10, drag_increments=40)


def kind_rows(kind: str, quick: bool):
    """The rows of one problem kind, one at a time (both codes; Hertz also ours in true
    2D).  A case ccx does not finish is a row with ``ccx_error`` and ours alone."""
    from dolfinx_friction.calculix import CcxError
    if kind == "hertz":
        cases = [(h, lambda h=h: hertz_scene(h, True), HERTZ_GROUPS, f"hertz_h{h}")
                 for h in (HERTZ_QUICK if quick else HERTZ_SIZES)]
    elif kind == "ironing":
        cases = [(size[1], lambda size=size: ironing_scene(size), IRONING_GROUPS,
                  f"ironing_{size[1]}x{size[2]}")
                 for size in (IRONING_QUICK if quick else IRONING_SIZES)]
    elif kind == "small3d":
        cases = [(2, lambda: C.scene(2, slide_increments=10), GROUPS, "small3d_n2")]
    else:
        raise SystemExit(f"--kinds: unknown kind {kind!r} (hertz, ironing, small3d)")
    for size, make, groups, label in cases:
        try:
            row = {"kind": kind, "size": size, **compare(make(), groups, label)}
        except CcxError as exc:
            _, ours = B.timed_run(make())
            row = {"kind": kind, "size": size, "ours": ours,
                   "ccx_error": str(exc).splitlines()[-1].strip()}
        if kind == "hertz":
            result, row["ours_2d"] = B.timed_run(hertz_scene(size, False))
            if "reactions" in row:
                # 2D reactions are per unit thickness: the twin carries LAYER times them
                twin = [np.asarray(r["cylinder_top"][:2]) for r in row["reactions"]]
                flat = [LAYER * np.asarray(i.reactions["cylinder_top"])
                        for i in result.increments]
                row["twin_rel"] = max(float(np.linalg.norm(a - b) / np.linalg.norm(a))
                                      for a, b in zip(twin, flat))
        yield row


def kinds_chart(rows, machine) -> Path:
    """CPU time against dofs, both codes, one panel per problem kind."""
    plt = B.pyplot()
    kinds = list(dict.fromkeys(r["kind"] for r in rows))
    fig, axes = plt.subplots(1, len(kinds), figsize=(4.5 * len(kinds), 4.2), dpi=100,
                             squeeze=False)
    for ax, kind in zip(axes[0], kinds):
        mine = [r for r in rows if r["kind"] == kind]
        x = [r["ours"]["dofs"] for r in mine]
        ax.loglog(x, [r["ours"]["cpu"] for r in mine], "o-", color="#1f77b4",
                  label="dolfinx_friction (3D)")
        both = [r for r in mine if "ccx_cpu" in r]
        ax.loglog([r["ours"]["dofs"] for r in both], [r["ccx_cpu"] for r in both], "s-",
                  color="#d62728", label="CalculiX (3D)")
        flat = [r for r in mine if "ours_2d" in r]
        if flat:
            ax.loglog([r["ours_2d"]["dofs"] for r in flat], [r["ours_2d"]["cpu"] for r in flat],
                      "^--", color="#2ca02c", label="dolfinx_friction, true 2D")
        ax.set_title(kind, fontsize=10)
        ax.set_xlabel("dofs")
        ax.set_ylabel("CPU seconds (whole analysis)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    fig.suptitle(f"against CalculiX, one core each (load {machine['load'][0]:.1f} on "
                 f"{machine['nproc']} cores, commit {machine['commit']})", fontsize=9)
    fig.tight_layout()
    path = B.FIGURES / "ccx_kinds.png"
    fig.savefig(path)
    plt.close(fig)
    return path


def kinds_report(rows, machine, load_end) -> str:
    from dolfinx_friction import calculix
    out = [
        "`benchmarks/bench_ccx.py --kinds hertz,ironing,small3d`: the problems CalculiX users "
        "run (issue 14), one `Scene` per case solved by dolfinx_friction and written by "
        f"`calculix.write_inp` for `{calculix.ccx_executable()}` (single-threaded, SPOOLES), "
        "one after the other in this process; an untimed warm-up run first.",
        "",
        "* hertz: `demos/hertz_cylinder.py`'s quarter cylinder on a block (its `build_mesh`, "
        "contact-zone size h), extruded by one layer of hexahedra (`_meshes.one_layer`, "
        f"thickness {LAYER}, u_z = 0 on both faces), K = 1e7, frictionless, pressed "
        f"{HERTZ_PRESS} in {HERTZ_INCREMENTS} increments; '2D' = the same quadrilaterals in "
        "plane strain (ours only: the deck writer has no 2D elements), its reactions x "
        "thickness against the twin's.",
        "* ironing: `test_calculix_nlgeom.ironing_mesh` (one hexahedron layer), linear bodies, "
        "mu = 0.3, press 10 + drag 40 increments.",
        "* small3d: the block on a foundation of `bench_cost.py` at n = 2, press 1 + slide 10 "
        "increments, mu = 0.3.",
        f"* {B.machine_line(machine, load_end)}",
        "* ours = the whole `run()`; ccx = the whole `ccx` process.  CPU: our process / the "
        "ccx child (`RUSAGE_CHILDREN`); the machine's 2 cores are shared with other jobs, so "
        "the CPU ratio is the load-independent one.",
        "",
    ]
    trs = []
    for r in rows:
        o = r["ours"]
        two = r.get("ours_2d")
        if "ccx_error" in r:
            trs.append([r["kind"], r["size"], f"{o['dofs']:,}",
                        f"{o['newton']} / {o['increments']}", f"ccx stops: {r['ccx_error']}",
                        B.fmt_s(o["cpu"]), "-", "-", B.fmt_s(o["wall"]), "-", "-", "-",
                        "-" if two is None else f"{two['dofs']:,}: {B.fmt_s(two['cpu'])} s CPU",
                        f"{o['load'][0]:.1f}"])
            continue
        trs.append([r["kind"], r["size"], f"{o['dofs']:,}", f"{o['newton']} / {o['increments']}",
                    f"{r['ccx_solves']} / {r['ccx_increments']}",
                    B.fmt_s(o["cpu"]), B.fmt_s(r["ccx_cpu"]), f"{o['cpu'] / r['ccx_cpu']:.2f}",
                    B.fmt_s(o["wall"]), B.fmt_s(r["ccx_wall"]),
                    f"{o['wall'] / r['ccx_wall']:.2f}", f"{100 * r['worst']:.3f}",
                    "-" if two is None else (f"{two['dofs']:,}: {B.fmt_s(two['cpu'])} s CPU, "
                                             f"{two['newton']} its, dR {r['twin_rel']:.1e}"),
                    f"{r['ccx_load'][0]:.1f} / {o['load'][0]:.1f}"])
    out.append(B.table(["kind", "size", "dofs", "our its / incs", "ccx solves / incs",
                        "our CPU [s]", "ccx CPU [s]", "CPU ratio", "our wall [s]",
                        "ccx wall [s]", "wall ratio", "max dR/R [%]", "ours in 2D",
                        "load ccx / ours"], trs))
    return "\n".join(out)


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
    ap.add_argument("--kinds", help="comma-separated problem kinds instead of the block on a "
                    "foundation: hertz, ironing, small3d")
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
    if args.kinds:
        rows = []
        for kind in args.kinds.split(","):
            for r in kind_rows(kind, args.quick):
                rows.append(r)
                o = r["ours"]
                print(f"{kind} {r['size']} dofs={o['dofs']}: ours {o['newton']} its cpu "
                      f"{o['cpu']:.1f} s wall {o['wall']:.1f} s phases {o['phases']} | ccx "
                      f"{r.get('ccx_solves')} solves cpu {r.get('ccx_cpu')} s wall "
                      f"{r.get('ccx_wall')} s {r.get('ccx_error', '')} | max dR/R "
                      f"{r.get('worst')} | 2D {r.get('ours_2d', {}).get('cpu')} | load "
                      f"{B.load_average():.1f}", flush=True)
                if args.json:
                    Path(args.json).write_text(json.dumps(rows, indent=1))
        text = kinds_report(rows, machine, B.load_average())
        figure = kinds_chart(rows, machine)
        text += f"\n\nChart (CPU time against dofs): `benchmarks/figures/{figure.name}`."
        print(text)
        if not args.no_results:
            B.write_section("Side by side with CalculiX: the problems its users run", text)
        return 0
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
