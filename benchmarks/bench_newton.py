"""Newton convergence of the exact ("consistent") and CalculiX's ("calculix") contact tangent.

    python benchmarks/bench_newton.py            # every demo scene as it is
    python benchmarks/bench_newton.py --quick    # only the first 4 increments of each demo (< 2 min)
    python benchmarks/bench_newton.py --demos incline,sliding_block --no-results

For every demo of ``demos/`` that exists (sliding_block, incline, hertz_cylinder,
hertz_sphere, cattaneo_mindlin, ironing), its scene file is run twice, serially and in
memory, with ``tangent = "consistent"`` and with ``tangent = "calculix"`` on every contact
pair; everything else (mesh, laws, increments, Newton tolerance ``newton_rtol`` = 1e-9 of
the first residual of each increment, ``pairing_iterations``) is the scene's own.  A demo
whose mesh file is missing has it built by the demo's ``build_mesh`` (default resolution)
into the scratch directory.

Per converged increment: Newton iterations, and the observed order
``q = log(e_{k+1}) / log(e_k)`` with ``e = r / r_0`` on the last two iterates with
``1e-10 < e < 1`` (``q ~ 2``: quadratic), and the scale-free three-point estimate
``q3 = log(e_{k+1}/e_k) / log(e_k/e_{k-1})`` on the last three iterates above 1e-10.  Reported per demo and
tangent: iterations per increment (median, mean, max), the median q, cutbacks, total Newton
iterations and CPU time.  Chart: ``e`` against the iteration for one increment per demo (the
increment where the two tangents differ most), both tangents:
``benchmarks/figures/newton_residuals.png``.

Target: median <= 3 Newton iterations per increment at the default tolerance.
"""
from __future__ import annotations

import argparse
import json
import dataclasses
import math
import statistics
import sys
import traceback
from pathlib import Path

import _bench as B  # noqa: I001
import numpy as np

DEMOS = ("sliding_block", "incline", "hertz_cylinder", "hertz_sphere", "cattaneo_mindlin",
         "ironing")
TANGENTS = ("consistent", "calculix")
E_MIN = 1e-10
QUICK_INCREMENTS = 4


def demo_scene(name: str):
    """The demo's scene (None if the demo does not exist), its mesh built if missing."""
    from dolfinx_friction.scene.toml import load_scene
    toml = B.DEMOS / f"{name}.toml"
    if not toml.exists() or not (B.DEMOS / f"{name}.py").exists():
        return None
    scene = load_scene(toml)
    mesh = Path(scene.mesh)
    if not mesh.exists():
        built = B.work_dir("newton") / mesh.name
        if not built.exists():
            B.demo_module(name).build_mesh(built)
        scene = dataclasses.replace(scene, mesh=built)
    return scene


def with_tangent(scene, tangent: str):
    contacts = tuple(dataclasses.replace(c, tangent=tangent) for c in scene.contacts)
    out = dataclasses.replace(scene.output, fields=False, contact_table=False)
    return dataclasses.replace(scene, contacts=contacts, output=out)


def order(residuals: list[float]) -> float:
    """``log(e_{k+1}) / log(e_k)`` on the last two iterates with 1e-10 < e < 1."""
    r0 = residuals[0]
    if r0 <= 0:
        return math.nan
    e = [r / r0 for r in residuals[1:] if E_MIN < r / r0 < 1.0]
    if len(e) < 2:
        return math.nan
    return math.log(e[-1]) / math.log(e[-2])


def order3(residuals: list[float]) -> float:
    """Scale-free estimate ``log(e_{k+1}/e_k) / log(e_k/e_{k-1})`` on the last three
    iterates with e > 1e-10 (e_0 = 1 included)."""
    r0 = residuals[0]
    e = [r / r0 for r in residuals if r0 > 0 and r / r0 > E_MIN]
    if len(e) < 3 or e[-2] == e[-3] or e[-1] == e[-2]:
        return math.nan
    return math.log(e[-1] / e[-2]) / math.log(e[-2] / e[-3])


def settling(changes: list[int]) -> int:
    """Iterations up to and including the last one that changed the contact state."""
    return max((k + 1 for k, c in enumerate(changes) if c), default=0)


def iterations_to(residuals: list[float], e: float) -> int:
    """First iteration with r <= e r0 (the last one if the increment converged above it)."""
    return next((k for k, r in enumerate(residuals) if r <= e * residuals[0]),
                len(residuals) - 1)


def run_demo(name: str, tangent: str, quick: bool) -> dict:
    scene = demo_scene(name)
    row = {"demo": name, "tangent": tangent}
    try:
        result, num = B.timed_run(with_tangent(scene, tangent),
                                  max_increments=QUICK_INCREMENTS if quick else None)
    except Exception as e:  # noqa: BLE001 - reported
        traceback.print_exc(limit=3)
        row.update(ok=False, error=f"{type(e).__name__}: {e}".splitlines()[0][:200])
        return row
    incs = [{"step": i.step, "increment": i.increment, "t": i.t, "iterations": i.iterations,
             "residuals": [float(r) for r in i.residuals], "q": order(i.residuals),
             "q3": order3(i.residuals), "changes": [a + b for a, b in zip(i.status_changes, i.face_changes)],
             "face_only": [a == 0 < b for a, b in zip(i.status_changes, i.face_changes)],
             "backtracks": list(i.backtracks),
             "active": i.active, "slipping": i.slipping} for i in result.increments]
    its = [i["iterations"] for i in incs]
    qs = [i["q"] for i in incs if math.isfinite(i["q"])]
    q3s = [i["q3"] for i in incs if math.isfinite(i["q3"])]
    row.update(num)
    row.update(ok=True, increments_data=incs, median_its=statistics.median(its),
               mean_its=float(np.mean(its)), max_its=max(its),
               median_q=statistics.median(qs) if qs else math.nan,
               min_q=min(qs) if qs else math.nan, dim=result.problem.gdim,
               median_q3=statistics.median(q3s) if q3s else math.nan,
               mu=max((c.mu for c in scene.contacts), default=0.0))
    return row


def chart(rows: list[dict], machine: dict) -> Path:
    plt = B.pyplot()
    demos = [d for d in dict.fromkeys(r["demo"] for r in rows)
             if all(r["ok"] for r in rows if r["demo"] == d)]
    n = max(len(demos), 1)
    cols = min(n, 3)
    nrows = math.ceil(n / cols)
    fig, axes = plt.subplots(nrows, cols, figsize=(5.2 * cols, 4.2 * nrows), dpi=100,
                             squeeze=False)
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    for ax, demo in zip(axes.ravel(), demos):
        by = {r["tangent"]: r for r in rows if r["demo"] == demo}
        # the increment (present in both runs) where the iteration counts differ most
        keys = {t: {(i["step"], round(i["t"], 9)): i for i in by[t]["increments_data"]}
                for t in by}
        common = set.intersection(*(set(k) for k in keys.values()))
        pick = max(common, key=lambda k: (keys["calculix"][k]["iterations"]
                                          - keys["consistent"][k]["iterations"],
                                          keys["consistent"][k]["iterations"], k[1]))
        for t, style in (("consistent", "o-"), ("calculix", "s--")):
            inc = keys[t][pick]
            r = np.array(inc["residuals"])
            q = inc["q"]
            ax.semilogy(range(len(r)), np.maximum(r / r[0], 1e-17), style, ms=4,
                        label=f"{t}: {inc['iterations']} its, q = {q:.2f}, q3 = {inc['q3']:.2f}")
            changed = [k + 1 for k, c in enumerate(inc["changes"]) if c]
            ax.semilogy(changed, np.maximum(r[changed] / r[0], 1e-17), "o", ms=9, mfc="none",
                        color="C3" if t == "consistent" else "C1", lw=0,
                        label=f"{t}: contact state changed" if changed else None)
        ax.axhline(1e-9, color="grey", lw=0.8, ls=":")
        inc = keys["consistent"][pick]
        ax.set_title(f"{demo}: step {inc['step']}, increment {inc['increment']} "
                     f"(t = {inc['t']:.3g})", fontsize=9)
        ax.set_xlabel("Newton iteration")
        ax.set_ylabel("r / r0")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    return B.save_figure(fig, "newton_residuals.png",
                         "Residual history, exact vs CalculiX tangent (tolerance 1e-9 r0, dotted; "
                         "rings: iterations that changed the contact state)", machine)


def report(rows, machine, load_end, quick, figure, missing) -> str:
    out = [
        "`benchmarks/bench_newton.py`" + (" --quick" if quick else "") + ": every demo scene "
        "as it is (mesh, law, K, mu, increments, tolerance 1e-9 r0), run with the exact "
        "(`tangent = \"consistent\"`) and with CalculiX's (`\"calculix\"`) tangent; serial, "
        "MUMPS." + (f" Quick mode: only the first {QUICK_INCREMENTS} increments of each demo."
                    if quick else ""),
        "",
        f"* {B.machine_line(machine, load_end)}",
        "* q = log(e_k+1)/log(e_k), e = r/r0, on the last two iterates with 1e-10 < e < 1, per "
        "increment (2 = quadratic); 'median q' over the increments that have two such iterates. "
        "This q is 2 only if e_k+1 ~ e_k^2, i.e. if the constant of quadratic convergence is ~1 "
        "in units of r0; where r0 is large against the final residuals it reads low although "
        "the convergence is quadratic, so 'q3' = log(e_k+1/e_k)/log(e_k/e_k-1) on the last three "
        "iterates above 1e-10 (scale-free) is given too.",
        "* time: CPU seconds of the run (single thread; wall times inflated by the other jobs).",
        "",
    ]
    if missing:
        out += [f"Demos not (yet) in `demos/` and so not run: {', '.join(missing)}.", ""]
    table_rows = []
    for r in rows:
        if not r["ok"]:
            table_rows.append([r["demo"], r["tangent"]] + ["-"] * 10 + ["failed: " + r["error"]])
            continue
        table_rows.append([
            r["demo"], r["tangent"], f"{r['dim']}D", f"{r['dofs']:,}", r["increments"],
            f"{r['median_its']:g}", f"{r['mean_its']:.2f}", r["max_its"],
            f"{r['median_q']:.2f}", f"{r['median_q3']:.2f}", r["cutbacks"], r["newton"],
            f"{B.fmt_s(r['cpu'])} (load {r['load'][0]:.1f})"])
    out.append(B.table(["demo", "tangent", "dim", "dofs", "increments", "median its/inc",
                        "mean its/inc", "max its", "median q", "median q3", "cutbacks",
                        "Newton its total", "CPU [s]"], table_rows, "llrrrrrrrrrrr"))
    out.append("")
    ok = [r for r in rows if r["ok"] and r["tangent"] == "consistent"]
    if ok:
        all_its = [i["iterations"] for r in ok for i in r["increments_data"]]
        med = statistics.median(all_its)
        out.append(f"Target: median <= 3 Newton iterations per increment (exact tangent). "
                   f"Measured: median {med:g} over all {len(all_its)} increments of "
                   f"{len(ok)} demos; per demo " + ", ".join(
                       f"{r['demo']} {r['median_its']:g}" for r in ok)
                   + (" -- **met**." if med <= 3 else " -- **missed**."))
        out.append("")
    if ok:
        out += [where_iterations_go(ok), ""]
    out.append(f"Chart: `benchmarks/figures/{figure.name}` (r/r0 per iteration of one increment "
               "per demo: the one where the CalculiX tangent needs the most extra iterations).")
    return "\n".join(out)


def where_iterations_go(rows: list[dict]) -> str:
    """Iterations per increment split into those that change the contact state (status
    open/stick/slip or master face of some slave node) and the tail after the last change."""
    med = lambda xs: f"{statistics.median(xs):g}"  # noqa: E731
    table_rows, every = [], []
    for r in rows:
        incs = r["increments_data"]
        every += incs
        settle = [settling(i["changes"]) for i in incs]
        tail = [i["iterations"] - s for i, s in zip(incs, settle)]
        late = sum(s > 1 for s in settle)
        changing = [f for i, s in zip(incs, settle) for f in i["face_only"][:s]]
        table_rows.append([
            r["demo"], len(incs), med([i["iterations"] for i in incs]), med(settle), med(tail),
            f"{100 * late / len(incs):.0f}", f"{100 * np.mean(changing) if changing else 0:.0f}",
            f"{np.mean([sum(i['backtracks']) for i in incs]):.2f}"]
            + [med([iterations_to(i["residuals"], e) for i in incs]) for e in (1e-3, 1e-6)])
    out = ["Where the iterations go (exact tangent): 'changing' = iterations up to the last one "
           "that changed the contact state of some slave node (open/stick/slip status or master "
           "face); 'tail' = the iterations after it, with the state of the converged increment "
           "already found; 'later changes' = increments whose state still changed after the "
           "first iteration; 'face only' = share of the changing iterations in which no status "
           "changed, only master faces (faceted masters); halvings = line-search backtracks "
           "per increment; the last two columns: "
           "iterations until r <= 1e-3 r0 and 1e-6 r0 (the default tolerance is 1e-9 r0).",
           "",
           B.table(["demo", "increments", "median its", "median changing", "median tail",
                    "later changes [%]", "face only [%]", "halvings/inc", "its to 1e-3 r0",
                    "its to 1e-6 r0"], table_rows, "lrrrrrrrrr"),
           ""]
    settle = [settling(i["changes"]) for i in every]
    tail = [i["iterations"] - s for i, s in zip(every, settle)]
    to_1e6 = med([iterations_to(i["residuals"], 1e-6) for i in every])
    late = 100 * np.mean([s > 1 for s in settle])
    out.append(f"All {len(every)} increments: median {med([i['iterations'] for i in every])} "
               f"iterations = median {med(settle)} changing the contact state + median "
               f"{med(tail)} after the last change; median {to_1e6} to 1e-6 r0.  In "
               f"{late:.0f} % of the increments the contact state still changes after the "
               "first iteration (nodes entering or leaving the contact zone, stick/slip at "
               "its edge, face switches on faceted masters); each change costs an iteration "
               "that only finds the state, often with line-search halvings.  A median of 3 "
               "at 1e-9 r0 would need the state right after the first iteration and a "
               "two-iteration tail in most increments.")
    return "\n".join(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--demos", default=",".join(DEMOS))
    ap.add_argument("--no-results", action="store_true")
    ap.add_argument("--json", help="also write the measured rows to this file")
    args = ap.parse_args(argv)
    machine = B.machine()
    rows, missing = [], []
    for name in args.demos.split(","):
        if demo_scene(name) is None:
            missing.append(name)
            print(f"{name}: no demo, skipped")
            continue
        try:  # warm-up (untimed): form compilation / cache loading for this demo's elements
            B.timed_run(with_tangent(demo_scene(name), "consistent"), max_increments=1)
        except Exception:  # noqa: BLE001 - the timed runs report failures
            pass
        for tangent in TANGENTS:
            r = run_demo(name, tangent, args.quick)
            rows.append(r)
            if r["ok"]:
                print(f"{name:16s} {tangent:10s} dofs={r['dofs']:7d} incs={r['increments']:3d} "
                      f"its/inc median={r['median_its']:g} mean={r['mean_its']:.2f} "
                      f"max={r['max_its']} q_med={r['median_q']:.2f} q3_med={r['median_q3']:.2f} cutbacks={r['cutbacks']} "
                      f"cpu={r['cpu']:.1f}s wall={r['wall']:.1f}s its={r['iterations']}",
                      flush=True)
            else:
                print(f"{name:16s} {tangent:10s} FAILED: {r['error']}", flush=True)
            if args.json:
                Path(args.json).write_text(json.dumps(rows, indent=1))
    figure = chart(rows, machine)
    print(f"chart: {figure}")
    text = report(rows, machine, B.load_average(), args.quick, figure, missing)
    print(text)
    if not args.no_results:
        B.write_section("Newton convergence: exact vs CalculiX tangent", text)


if __name__ == "__main__":
    sys.exit(main())
