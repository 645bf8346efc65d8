"""Speed vs accuracy on the ironing: penalty K against the augmented Lagrangian.

    python benchmarks/bench_ironing_accuracy.py                 # the series (~2 min CPU)
    python benchmarks/bench_ironing_accuracy.py --quick         # 4 points (< 1 min)
    python benchmarks/bench_ironing_accuracy.py --from-json F   # redraw from a saved run

The scene: the ironing demo (``demos/ironing.py``'s mesh and ``ironing.toml``: a stiff
elastic die, E = 1e4, pressed 0.5 into a soft block, E = 10, and dragged 4 along it,
mu = 0.3, slave = the block top), built by the stability maps' ``ironing_scene``
(``benchmarks/stability/_scenes.py``) at ``nx`` x ``ny`` block elements (h = 20 / nx) and
``n_arc`` die elements; line search on (the package default), 4 press increments, the
package's default stick slope lambda = 1 E/h (the maps' cases without ``lam`` use
CalculiX's E/2 = 0.125 E/h here, with which the augmented tangential multipliers converge
too slowly for the reference's tolerance: 25 updates do not reach 1e-8).

Series: penalty K = k E/h for k = 1, 10, 100, 1000 and the augmented Lagrangian
(``method = "augmented"``, default tolerance 1e-4 of the spacing) at k = 1 and 10, each
with 16, 32 and 64 drag increments.  Measured: the die's normal (press) force Fn and
tangential (friction) force Ft on its top face, each averaged over the second half of the
drag (the steady part), and the largest overclosure / slave spacing of the run.  Error:
against the **reference**, the augmented Lagrangian at k = 10 with the tolerance 1e-7 of
the spacing and 128 drag increments on the same mesh (so the error is that of the contact
method and the increment, not of the mesh).  Its own uncertainty: how far two neighbours land
from it (``CHECKS``: the same with 256 increments and the default tolerance, the stiffest
penalty with 128), drawn as a dotted line in the chart.  Time: CPU seconds of the whole ``run()`` (:func:`_bench.timed_run`).
Chart: ``benchmarks/figures/ironing_accuracy.png``; section "Ironing: speed vs accuracy" of
``RESULTS.md``.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import _bench as B  # noqa: I001  (threads, sys.path)

sys.path.insert(0, str(B.BENCH / "stability"))
import _scenes  # noqa: E402  (the maps' ironing scene)

MESH = dict(nx=80, ny=16, n_arc=32)
STICK = 1.0  # stick slope lambda / (E/h): the package default
#: (k, method): K = k E/h, penalty or augmented Lagrangian at its default tolerance
SERIES = ((1, "penalty"), (10, "penalty"), (100, "penalty"), (1000, "penalty"),
          (1, "augmented"), (10, "augmented"))
INCREMENTS = (16, 32, 64)
QUICK_SERIES = ((10, "penalty"), (10, "augmented"))
QUICK_INCREMENTS = (16, 32)
REFERENCE = dict(k=10, method="augmented", increments=128, augmented_tolerance=1e-7)
CHECKS = ((10, "augmented", 256), (1000, "penalty", 128))


def case(k: float, method: str, increments: int, **extra) -> dict:
    return dict(family="ironing", k=k, contact_method=method, increments=increments,
                line_search=True, lam=STICK, **MESH, **extra)


def measure(k: float, method: str, increments: int, **extra) -> dict:
    """One run: CPU time, Newton iterations and the steady forces (see the module doc)."""
    row = dict(k=k, method=method, increments=increments, **extra)
    scene, info = _scenes.ironing_scene(case(k, method, increments, **extra))
    try:
        result, num = B.timed_run(scene)
    except Exception as e:  # noqa: BLE001 - a failed point is reported, not fatal
        row.update(ok=False, error=f"{type(e).__name__}: {e}".splitlines()[0][:200])
        return row
    drag = [inc for inc in result.increments if inc.step == 1]
    half = drag[len(drag) // 2:]
    force = [inc.reactions[info["reaction"]] for inc in half]
    row.update(ok=True, cpu=num["cpu"], wall=num["wall"], newton=num["newton"],
               cutbacks=num["cutbacks"], load=num["load"][0], h=info["h"],
               Fn=sum(abs(f[1]) for f in force) / len(force),
               Ft=sum(abs(f[0]) for f in force) / len(force),
               overclosure=max(max(inc.penetration.values(), default=0.0)
                               for inc in result.increments))
    return row


def errors(rows: list[dict], ref: dict) -> None:
    for r in rows:
        if r["ok"]:
            r["err_Fn"] = abs(r["Fn"] / ref["Fn"] - 1.0)
            r["err_Ft"] = abs(r["Ft"] / ref["Ft"] - 1.0)


def label(r: dict) -> str:
    return f"K = {r['k']} E/h" + (", augmented" if r["method"] == "augmented" else "")


def uncertainty(checks: list[dict], key: str) -> float:
    return max((c[key] for c in checks if c["ok"]), default=math.nan)


def chart(rows: list[dict], checks: list[dict], title: str) -> Path:
    plt = B.pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.8), dpi=100)
    colours = dict(zip(SERIES, ("#1f77b4", "#2ca02c", "#ff7f0e", "#d62728", "#8c564b",
                                "#9467bd")))
    for ax, key, ylabel in ((axes[0], "err_Ft", "|Ft / Ft(ref) - 1| (friction force)"),
                            (axes[1], "err_Fn", "|Fn / Fn(ref) - 1| (press force)"),
                            (axes[2], "overclosure", "largest overclosure / slave spacing")):
        for k, method in SERIES:
            pts = sorted((r["cpu"], max(r[key], 1e-7), r["increments"]) for r in rows
                         if r["ok"] and (r["k"], r["method"]) == (k, method))
            if not pts:
                continue
            ax.plot([p[0] for p in pts], [p[1] for p in pts],
                    "--" if method == "augmented" else "-",
                    marker="s" if method == "augmented" else "o", color=colours[k, method],
                    ms=5, lw=1, label=label(dict(k=k, method=method)))
            for x, y, n in pts:
                ax.annotate(str(n), (x, y), fontsize=6, xytext=(3, 3), textcoords="offset points")
        if key != "overclosure":
            ax.axhline(uncertainty(checks, key), color="grey", ls=":", lw=1,
                       label="the reference's uncertainty")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU time of the run [s] (labels: drag increments)")
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3, which="both")
    axes[0].legend(fontsize=7)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    path = B.FIGURES / "ironing_accuracy.png"
    fig.savefig(path)
    plt.close(fig)
    return path


def report(rows: list[dict], ref: dict, checks: list[dict], machine: dict, load_end: float,
           figure: Path) -> str:
    h = ref["h"]
    out = [
        "`benchmarks/bench_ironing_accuracy.py`: the ironing demo (stiff elastic die pressed 0.5 "
        "into a soft block and dragged 4 along it, mu = 0.3; the stability maps' "
        f"`ironing_scene` at nx = {MESH['nx']}, ny = {MESH['ny']}, n_arc = {MESH['n_arc']}: "
        f"slave spacing h = {h:g}), stick slope {STICK:g} E/h (the default), line search on, 4 "
        "press increments.  Fn, Ft = the die "
        "top's normal and tangential reaction averaged over the second half of the drag; "
        "errors against the reference: the augmented Lagrangian at K = 10 E/h with tolerance "
        "1e-7 of the spacing and 128 drag increments, same mesh "
        f"(Fn = {ref['Fn']:.6g}, Ft = {ref['Ft']:.6g}, {ref['newton']} Newton iterations, "
        f"{B.fmt_s(ref['cpu'])} s CPU).  Overclosure = the largest of the run / h.  The "
        "reference's uncertainty, from its neighbours: " + "; ".join(
            f"{label(c)}, {c['increments']} incr.: Ft {100 * c['err_Ft']:.2g} %, Fn "
            f"{100 * c['err_Fn']:.2g} % off" for c in checks if c["ok"]) + ".",
        "",
        f"* {B.machine_line(machine, load_end)}",
        "* time = CPU seconds of the whole `run()` (set-up included) of the single-threaded "
        "process; wall seconds in the table.",
        "",
    ]
    rows_t = []
    for r in rows:
        name = label(r) + f", {r['increments']} incr."
        if not r["ok"]:
            rows_t.append([name, "-", "-", "-", "-", "-", "-", "-", "failed: " + r["error"][:60]])
            continue
        rows_t.append([name, f"{r['newton']}" + (f" ({r['cutbacks']} cb)" if r["cutbacks"] else ""),
                       f"{r['Ft']:.5g}", f"{100 * r['err_Ft']:.3g}", f"{r['Fn']:.5g}",
                       f"{100 * r['err_Fn']:.3g}", f"{100 * r['overclosure']:.2g}",
                       B.fmt_s(r["cpu"]), B.fmt_s(r["wall"])])
    out.append(B.table(["run", "Newton its", "Ft", "err Ft [%]", "Fn", "err Fn [%]",
                        "overclosure [% h]", "CPU [s]", "wall [s]"], rows_t))
    out.append("")
    ok = [r for r in rows if r["ok"]]
    for key, what in (("err_Ft", "friction force"), ("err_Fn", "press force")):
        pts = [(r["cpu"], r[key]) for r in ok]
        front = [ok[i] for i in B.pareto(pts)]
        out.append(f"Pareto front ({what}): " + "; ".join(
            f"{label(r)}, {r['increments']} incr. ({100 * r[key]:.2g} % in "
            f"{B.fmt_s(r['cpu'])} s)" for r in front))
        out.append("")
    out.append(f"Chart: `benchmarks/figures/{figure.name}`")
    return "\n".join(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="4 points, coarse reference")
    ap.add_argument("--no-results", action="store_true", help="do not touch RESULTS.md")
    ap.add_argument("--json", help="write the rows (and machine) to this file")
    ap.add_argument("--from-json", help="no runs: report and chart the rows of this file")
    args = ap.parse_args(argv)
    if args.from_json:
        data = json.loads(Path(args.from_json).read_text())
        machine, rows, ref, load_end = data["machine"], data["rows"], data["ref"], data["load_end"]
        checks = data["checks"]
    else:
        machine = B.machine()
        B.timed_run(_scenes.ironing_scene(case(10, "penalty", 4))[0])  # warm-up, untimed
        ref = measure(**REFERENCE)
        if not ref["ok"]:
            sys.exit(f"the reference run failed: {ref['error']}")
        print("reference:", json.dumps(ref), flush=True)
        checks = [] if args.quick else [measure(*c) for c in CHECKS]
        rows = []
        for k, method in (QUICK_SERIES if args.quick else SERIES):
            for n in (QUICK_INCREMENTS if args.quick else INCREMENTS):
                rows.append(measure(k, method, n))
                r = rows[-1]
                print(f"{label(r)}, {n} incr.: " + (
                    f"Fn {r['Fn']:.6g} Ft {r['Ft']:.6g} overclosure {r['overclosure']:.2e} "
                    f"newton {r['newton']} cb {r['cutbacks']} cpu {r['cpu']:.2f} s"
                    if r["ok"] else f"FAILED {r['error']}"), flush=True)
        load_end = B.load_average()
        if args.json:
            Path(args.json).write_text(json.dumps(dict(machine=machine, rows=rows, ref=ref,
                                                       checks=checks, load_end=load_end),
                                                  indent=1))
    errors(rows + checks, ref)
    figure = chart(rows, checks, f"ironing (demo, nx = {MESH['nx']}): error against CPU time, "
                         f"reference = augmented, tolerance 1e-7, 128 increments "
                         f"(load {machine['load'][0]:.1f} on {machine['nproc']} cores)")
    text = report(rows, ref, checks, machine, load_end, figure)
    print(text)
    if not args.no_results and not args.quick:
        B.write_section("Ironing: speed vs accuracy", text)


if __name__ == "__main__":
    main()
