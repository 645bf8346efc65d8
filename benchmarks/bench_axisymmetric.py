"""Hertz sphere: the axisymmetric meridian section against the 3D eighth of a sphere, cost at
equal accuracy.

    python benchmarks/bench_axisymmetric.py             # both series (about 2 minutes)
    python benchmarks/bench_axisymmetric.py --no-results

The 3D problem of ``bench_hertz.py`` (the eighth of a sphere of ``demos/hertz_sphere.py``'s
``build_mesh``, R = 10, tetrahedra refined at the pole, top pushed by 0.05 and held
laterally, rigid plane, frictionless, E = 1000, nu = 0.3, one increment, P1, K = 10 E/h) and
the same sphere as an axisymmetric section (``plane = "axisymmetric"``: the quarter disk of
:func:`dolfinx_friction.reference.meshes.sphere_section`, triangles refined alike, the
nodes on the axis at u_r = 0), contact-zone element size h = 0.5 / n.

Errors of the elliptic fit p^2 = p0^2 (1 - r^2/a^2) of the nodal pressures (``bench_hertz.
measure``), against Hertz for the measured load and against the converged section (the
finest axisymmetric run): both bodies are a finite sphere held at its top, which Hertz's
half-space approximates to about 1 % at a/R = 0.07, so the discretisation error is measured
against the converged section.  Cost at equal accuracy: for each 3D run, the cheapest
axisymmetric run whose errors (p0 and a, against the converged section) are no larger.
Time: CPU seconds of the whole ``run()`` (set-up included, mesh generation excluded).
"""
from __future__ import annotations

import argparse
import math
import sys

import _bench as B  # noqa: I001  (threads, sys.path)
import bench_hertz as H

SERIES = {"axi": (2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64), "3d": (2, 3, 4, 6, 8, 12)}
K = 10


def run_series(problem: str, ns, log) -> list[dict]:
    B.timed_run(H.scene(problem, ns[0], 1, K))  # warm-up: form compilation, caches
    rows = []
    for n in ns:
        H.MESHES[problem](n)
        result, num = B.timed_run(H.scene(problem, n, 1, K))
        row = {"problem": problem, "n": n, "h": H.A_NOMINAL / n, **num,
               **H.measure(result, problem)}
        del result
        row["p0_ratio"], row["a_ratio"] = row["p0"] / row["p0_ref"], row["a"] / row["a_ref"]
        rows.append(row)
        log(row)
    return rows


def against(rows: list[dict], reference: dict) -> None:
    """Errors against the converged section (``reference``: its finest run)."""
    for r in rows:
        r["dev_p0"] = abs(r["p0_ratio"] / reference["p0_ratio"] - 1.0)
        r["dev_a"] = abs(r["a_ratio"] / reference["a_ratio"] - 1.0)


def equal_accuracy(axi: list[dict], full: list[dict]) -> list[tuple[dict, dict]]:
    """For each 3D run, the cheapest axisymmetric run at least as accurate (p0 and a)."""
    out = []
    for r in full:
        good = [q for q in axi if q["dev_p0"] <= r["dev_p0"] and q["dev_a"] <= r["dev_a"]]
        if good:
            out.append((r, min(good, key=lambda q: q["cpu"])))
    return out


def chart(axi: list[dict], full: list[dict], pairs, machine: dict):
    plt = B.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), dpi=100)
    for ax, key, label in ((axes[0], "dev_p0", "p0"), (axes[1], "dev_a", "a")):
        for rows, name, style in ((axi[:-1], "axisymmetric section", "o-"),
                                  (full, "3D eighth of a sphere", "s-")):
            pts = [(r["cpu"], max(r[key], 1e-5), r["n"]) for r in rows]
            line, = ax.plot([p[0] for p in pts], [p[1] for p in pts], style, ms=5,
                            label=name)
            for x, y, n in pts:
                ax.annotate(f"{n}", (x, y), fontsize=7, xytext=(3, 3),
                            textcoords="offset points", color=line.get_color())
        for r, q in pairs:
            ax.annotate("", (q["cpu"], max(q[key], 1e-5)), (r["cpu"], max(r[key], 1e-5)),
                        arrowprops=dict(arrowstyle="->", color="grey", lw=0.7))
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU time of the run [s] (single thread, set-up included)")
        ax.set_ylabel(f"relative error in {label} (elliptic fit) vs converged section")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
    return B.save_figure(fig, "hertz_axisymmetric_vs_3d.png",
                         "Hertz sphere, P1, K = 10 E/h (labels: n = 0.5/h; arrows: 3D run -> "
                         "cheapest section at least as accurate)", machine, fontsize=9)


def report(axi, full, pairs, machine, load_end, figure) -> str:
    ref = axi[-1]
    out = ["`benchmarks/bench_axisymmetric.py`: "
           + "\n\n".join(p.replace("\n", " ") for p in __doc__.split("\n\n")[2:5]), "",
           f"* {B.machine_line(machine, load_end)}",
           f"* converged section (n = {ref['n']}, {ref['dofs']:,} dofs): p0 fit / Hertz = "
           f"{ref['p0_ratio']:.4f}, a fit / Hertz = {ref['a_ratio']:.4f}", ""]
    rows = []
    for r in full + axi:
        rows.append(["3D" if r["problem"] == "3d" else "section", r["n"], f"{r['h']:.4g}",
                     f"{r['dofs']:,}", r["newton"],
                     f"{100 * (r['p0_ratio'] - 1):+.2f}", f"{100 * (r['a_ratio'] - 1):+.2f}",
                     f"{100 * r['dev_p0']:.3f}", f"{100 * r['dev_a']:.3f}",
                     B.fmt_s(r["cpu"]), B.fmt_s(r["wall"])])
    out.append(B.table(["model", "n", "h", "dofs", "Newton", "p0 fit vs Hertz [%]",
                        "a fit vs Hertz [%]", "err p0 [%]", "err a [%]", "CPU [s]",
                        "wall [s]"], rows))
    out += ["", "Cost at equal accuracy (err p0 and err a against the converged section):", ""]
    out.append(B.table(["3D run", "its errors p0 / a [%]", "CPU [s]", "cheapest section",
                        "its errors p0 / a [%]", "CPU [s]", "CPU ratio"],
                       [[f"n = {r['n']} ({r['dofs']:,} dofs)",
                         f"{100 * r['dev_p0']:.2f} / {100 * r['dev_a']:.2f}",
                         B.fmt_s(r["cpu"]), f"n = {q['n']} ({q['dofs']:,} dofs)",
                         f"{100 * q['dev_p0']:.2f} / {100 * q['dev_a']:.2f}",
                         B.fmt_s(q["cpu"]), f"{r['cpu'] / q['cpu']:.0f}x"]
                        for r, q in pairs]))
    out += ["", f"Chart: `benchmarks/figures/{figure.name}`"]
    return "\n".join(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-results", action="store_true", help="do not touch RESULTS.md")
    args = ap.parse_args(argv)
    machine = B.machine()

    def log(r):
        print(f"{r['problem']:3s} n={r['n']:3d} dofs={r['dofs']:7d} newton={r['newton']:3d} "
              f"p0/Hertz={r['p0_ratio']:.4f} a/Hertz={r['a_ratio']:.4f} cpu={r['cpu']:7.2f}s "
              f"load={r['load'][0]:.1f}", flush=True)
    axi = run_series("axi", SERIES["axi"], log)
    full = run_series("3d", SERIES["3d"], log)
    for rows in (axi, full):
        against(rows, axi[-1])
    pairs = equal_accuracy(axi[:-1], full)
    figure = chart(axi, full, pairs, machine)
    text = report(axi, full, pairs, machine, B.load_average(), figure)
    print(text)
    if not math.isfinite(axi[-1]["p0_ratio"]):
        raise SystemExit("the converged section has no fit")
    if not args.no_results:
        B.write_section("Hertz: axisymmetric section vs 3D", text)


if __name__ == "__main__":
    sys.exit(main())
