"""From 15k to a million dofs: a frictional 3D scene file run by the command line, the
linear solver chosen by ``[solver] linear = "auto"``.

    python benchmarks/bench_scale.py                 # n = 6, 9, 12, 16, 21, 29 (~1.6e4 ... 1.06e6 dofs; long)
    python benchmarks/bench_scale.py --quick         # n = 3, 5 (< 1 min)
    python benchmarks/bench_scale.py --sizes 6,9 --ccx-max 9 --no-results

Scene: ``bench_cost.py``'s block on a foundation at resolution n (2n x 2n x n hexahedra on
3n x 3n x n, Q4 slave faces), E = 1000, nu = 0.3, CalculiX's K = 50 E and lambda = E/2,
mu = 0.3; press 0.005 (1 increment), slide 0.02 (2 increments).  Each size is a
scene file (``[solver] linear = "auto"``: MUMPS up to 120k unknowns, then GMRES + GAMG) run
as users run it, ``python -m dolfinx_friction run SCENE --quiet`` in its own process,
serial; its summary.json gives the wall time, Newton iterations, preconditioner set-ups
(factorisations or GAMG set-ups), Krylov iterations, peak memory and the solver chosen; history.csv the reactions.  Up to
``--ccx-max`` the same scene goes through ``ccx`` (single-threaded, one core) in the same
call.

Checked along the sequence: at the end of the slide at least 95 % of the closed slave nodes
slip, each carrying ``|f_T| = mu f_N`` (contact.csv, to 1e-9); the press force converges as the mesh is refined (the
change from one size to the next shrinks); at every size where ccx ran, the reactions of
every increment agree with CalculiX's.
"""
from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
import time
from pathlib import Path

import _bench as B  # noqa: I001  (before numpy: its settings)
import numpy as np

import bench_cost as C
from dolfinx_friction.reference.cases import block_on_foundation_toml

FULL, QUICK = (6, 9, 12, 16, 21, 29), (3, 5)
MU = 0.3

CONTACT = 'K = "calculix"\nstick_slope = "calculix"'
OUTPUT = """fields = false
contact_table = true
reactions = ["block_top", "foundation_bottom"]
[solver]
linear = "auto"
"""


def scene_file(n: int) -> Path:
    path = B.work_dir("scale") / f"boxes_n{n}.toml"
    path.write_text(block_on_foundation_toml(
        str(C.two_boxes_mesh(n)), title=f"block on a foundation, n = {n}", mu=MU,
        press=-C.PRESS, slide=C.SLIDE, contact=CONTACT, output=OUTPUT))
    return path


def ours(path: Path) -> dict:
    """Run the scene file by the command line; the numbers of its summary and history."""
    out = path.with_suffix("")
    load0 = B.load_average()
    t0 = time.perf_counter()
    c0 = B.children_cpu()
    proc = subprocess.run([sys.executable, "-m", "dolfinx_friction", "run", str(path), "--out",
                           str(out), "--quiet"], capture_output=True, text=True)
    wall, cpu = time.perf_counter() - t0, B.children_cpu() - c0
    if proc.returncode != 0:
        raise RuntimeError(f"{path.name}: exit {proc.returncode}: {proc.stderr.strip()[-400:]}")
    summary = json.loads((out / "summary.json").read_text())
    with open(out / "history.csv", newline="") as f:
        history = list(csv.DictReader(f))
    return {"dofs": summary["dofs"], "wall": wall, "cpu": cpu, "load": [load0, B.load_average()],
            "newton": summary["newton_iterations"], "cutbacks": summary["cutbacks"],
            "chosen": summary["resolved"]["solver"]["chosen"],
            "setups": summary["linear_solves"]["preconditioner_setups"],
            "krylov": summary["linear_solves"]["krylov_iterations"],
            "memory_mib": summary["peak_memory_mib"],
            "phases": summary["wall_time_per_phase_s"],
            "R": [[float(r[f"R_block_top_{a}"]) for a in "xyz"] for r in history],
            "t": [float(r["t"]) for r in history],
            "closed": int(history[-1]["active"]), "slipping": int(history[-1]["slipping"]),
            "coulomb": coulomb(out / "contact.csv")}


def coulomb(table: Path) -> float:
    """The largest ``| |f_T| - mu f_N | / (mu f_N)`` over the slipping slave nodes of the
    last increment in contact.csv."""
    with open(table, newline="") as f:
        rows = list(csv.DictReader(f))
    last = max((int(r["step"]), int(r["increment"])) for r in rows)
    worst = 0.0
    for r in rows:
        if (int(r["step"]), int(r["increment"])) == last and r["status"] == "slip":
            fT = np.linalg.norm([float(r[f"tangential_force_{a}"]) for a in "xyz"])
            fN = float(r["normal_force"])
            worst = max(worst, abs(fT - MU * fN) / (MU * fN))
    return worst


def ccx(path: Path, n: int) -> dict:
    """The same scene by CalculiX: wall and CPU time, and each increment's top reaction."""
    from dolfinx_friction.reference import calculix
    from dolfinx_friction.scene.toml import load_scene
    inp = B.work_dir("scale") / f"boxes_n{n}.inp"
    calculix.write_inp(load_scene(path), inp)
    c0 = B.children_cpu()
    run = calculix.run_ccx(inp, details=True, threads=1, timeout=7200)
    R = [run.reactions[s][k]["block_top"].tolist()
         for s in sorted(run.reactions) for k in sorted(run.reactions[s])]
    return {"wall": run.wall, "cpu": B.children_cpu() - c0, "R": R}


def checks(rows: list[dict]) -> list[str]:
    """What the sequence shows; raises if a check fails."""
    lines = []
    for r in rows:
        o = r["ours"]
        Rx, _, Rz = o["R"][-1]
        closed, slipping = slip_counts(o, r["n"])
        assert slipping >= 0.95 * closed > 0 and o["coulomb"] < 1e-9, (r["n"], o["coulomb"])
        lines.append(f"n = {r['n']}: {slipping} of {closed} closed slave nodes slip at the end, "
                     f"each with |f_T| = mu f_N to {o['coulomb']:.1e}; |R_x| / |R_z| = "
                     f"{abs(Rx) / abs(Rz):.4f} (slip directions fan out a little; a few "
                     f"corner nodes stick)")
        if "ccx" in r:
            worst = max(relative(a, b) for a, b in zip(o["R"], r["ccx"]["R"]))
            assert worst < 1e-3, (r["n"], worst)
            r["ccx_worst"] = worst
    press = [abs(r["ours"]["R"][0][2]) for r in rows]
    changes = [abs(b - a) / abs(b) for a, b in zip(press, press[1:])]
    for r, c in zip(rows[1:], changes):
        r["press_change"] = c
    assert all(b < a for a, b in zip(changes, changes[1:])), changes
    return lines


def slip_counts(o: dict, n: int) -> tuple[int, int]:
    """Closed and slipping slave nodes at the end of the slide (from the run's history.csv
    for rows of a log written before they were counted)."""
    if "closed" not in o:
        with open(B.work_dir("scale") / f"boxes_n{n}" / "history.csv", newline="") as f:
            last = list(csv.DictReader(f))[-1]
        o["closed"], o["slipping"] = int(last["active"]), int(last["slipping"])
    return o["closed"], o["slipping"]


def relative(ours: list[float], theirs: list[float]) -> float:
    a, b = np.asarray(ours), np.asarray(theirs)
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def chart(rows: list[dict], machine: dict) -> Path:
    plt = B.pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.4), dpi=100)
    dofs = [r["ours"]["dofs"] for r in rows]
    marker = ["o" if r["ours"]["chosen"] == "direct" else "s" for r in rows]
    for i, r in enumerate(rows):
        o = r["ours"]
        axes[0].loglog(dofs[i], o["wall"], marker[i], color="C0",
                       label="dolfinx_friction" if i == 0 else None)
        if "ccx" in r:
            axes[0].loglog(dofs[i], r["ccx"]["wall"], "^", color="C3",
                           label="CalculiX" if "ccx" not in rows[max(i - 1, 0)] or i == 0
                           else None)
        axes[1].loglog(dofs[i], o["memory_mib"], marker[i], color="C0")
        axes[2].semilogx(dofs[i], o["newton"], marker[i], color="C0",
                         label="Newton" if i == 0 else None)
        axes[2].semilogx(dofs[i], o["krylov"] / max(o["newton"], 1), marker[i], color="C2",
                         label="Krylov per Newton" if i == 0 else None)
    axes[0].set(xlabel="dofs", ylabel="wall time [s]", title="time (o MUMPS, s GMRES + GAMG)")
    axes[1].set(xlabel="dofs", ylabel="peak memory [MiB]", title="memory")
    axes[2].set(xlabel="dofs", ylabel="iterations", title="iterations")
    axes[0].legend()
    axes[2].legend()
    return B.save_figure(fig, "scale.png", f"press and slide of a block on a foundation, "
                         f"mu = {MU}, [solver] auto; {machine['date']}", machine, fontsize=12)


def report(rows: list[dict], lines: list[str], machine: dict, load_end: float,
           figure: Path, note: str = "") -> str:
    table = []
    for r in rows:
        o = r["ours"]
        c = r.get("ccx")
        table.append([r["n"], f"{o['dofs']:,}", o["chosen"], o["newton"], o["cutbacks"],
                      o.get("setups", o.get("factorisations")), o["krylov"], B.fmt_s(o["wall"]), B.fmt_s(o["cpu"]),
                      f"{o['memory_mib']:,.0f}",
                      f"{B.fmt_s(c['wall'])} / {B.fmt_s(c['cpu'])}" if c else "-",
                      f"{o['wall'] / c['wall']:.2f} / {o['cpu'] / c['cpu']:.2f}" if c else "-",
                      f"{r['ccx_worst']:.1e}" if c else "-",
                      f"{r['press_change']:.2e}" if "press_change" in r else "-",
                      f"{o['load'][0]:.1f}"])
    return (__doc__.split("\n\n", 2)[2].strip() + "\n\n* " + B.machine_line(machine, load_end)
            + (f"\n* {note}" if note else "")
            + "\n\n" + B.table(["n", "dofs", "solver", "Newton its", "cutbacks",
                                 "factorisations / AMG set-ups", "Krylov its", "wall [s]", "CPU [s]",
                                 "peak memory [MiB]", "ccx wall / CPU [s]",
                                 "ours / ccx (wall / CPU)",
                                 "reactions vs ccx", "press force change", "load"], table)
            + "\n\n" + "\n".join("* " + line for line in lines)
            + f"\n\n![scale]({figure.relative_to(B.ROOT / 'benchmarks')})\n")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--sizes")
    ap.add_argument("--ccx-max", type=int, default=12, help="largest n run by ccx too")
    ap.add_argument("--no-results", action="store_true")
    ap.add_argument("--from-log", help="no runs: the rows printed by an earlier run (its "
                                       "stdout), reported and charted")
    ap.add_argument("--note", default="", help="a line for the report (where logged rows "
                                               "come from)")
    args = ap.parse_args(argv)
    sizes = [int(s) for s in args.sizes.split(",")] if args.sizes else (
        QUICK if args.quick else FULL)
    machine = B.machine()
    rows = []
    if args.from_log:
        rows = [json.loads(line) for line in Path(args.from_log).read_text().splitlines()
                if line.startswith("{")]
        sizes = []
    for n in sizes:
        path = scene_file(n)
        row = {"n": n}
        if n <= args.ccx_max:
            row["ccx"] = ccx(path, n)
        row["ours"] = ours(path)
        rows.append(row)
        print(json.dumps({k: v for k, v in row.items()}), flush=True)
    lines = checks(rows)
    print("\n".join(lines))
    if not args.no_results:
        figure = chart(rows, machine)
        B.write_section("From 15k to a million dofs: a scene file, [solver] auto",
                        report(rows, lines, machine, B.load_average(), figure, args.note))


if __name__ == "__main__":
    main()
