"""Small scenes, start-up included: the whole command against ``ccx`` on the same deck.

    python benchmarks/bench_small.py                     # both scenes, 5 repeats, RESULTS.md
    python benchmarks/bench_small.py --repeats 3 --no-results
    python benchmarks/bench_small.py --scenes boxes      # only the issue-14 scene

Arguments: ``--scenes`` (comma-separated, from ``boxes`` and ``sliding_block``),
``--repeats`` (runs of every command; the minimum is reported, default 5),
``--no-results`` (print the section, leave ``benchmarks/RESULTS.md`` alone).

Scenes (both 3D, first-order hexahedra, mu = 0.3, 1 press increment + 10 slide increments):

* ``boxes`` -- the scene of ``bench_cost.py`` / ``bench_ccx.py`` at n = 2 (801 dofs,
  25 slave nodes; K and lambda by CalculiX's rules), with 10 slide increments: the
  "1k dofs, 11 increments" line of issue 14;
* ``sliding_block`` -- the demo ``demos/sliding_block.toml`` as shipped (1,860 dofs).

Each is written as a scene file (TOML + mesh) and as a CalculiX deck
(:func:`dolfinx_friction.reference.calculix.write_inp` of the same :class:`Scene`) in
``$BENCH_WORK/small``.  Timed, alternately, each in a fresh process, as a user runs them:

* ``ours``: ``python -m dolfinx_friction run scene.toml --quiet`` (all outputs: fields
  per increment, contact table, history, summary);
* ``ours, no fields``: the same with ``--set output.fields=false``;
* ``ours, cold mesh cache``: ``ours`` with an empty mesh cache (:mod:`dolfinx_friction.io.mesh_cache`:
  gmsh reads the mesh); the other runs of ours find the mesh in a cache of their own
  (``$BENCH_WORK/small/mesh_cache``), as every run after a scene's first does;
* ``ccx``: ``ccx -i deck`` (one thread, as ``calculix.run_ccx`` runs it);
* the floors: ``python -c pass`` and ``python -c "import dolfinx_friction.scene.runner"``.

Wall time (``time.perf_counter``) and CPU time (``getrusage(RUSAGE_CHILDREN)``) of each
command; the minimum over the repeats (the machine is shared: the minimum is the least
disturbed run); the 1-min load average at the start and the end.  The split of our time
comes from the run's own ``summary.json`` (``wall_time_per_phase_s``) and from the import
floor.  No pass/fail: the target (ours <= 1x ccx's wall time) is read off the table.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import _bench as B  # noqa: I001

import bench_cost as C
from dolfinx_friction.reference.cases import block_on_foundation_toml

SCENES = ("boxes", "sliding_block")
BOXES_TITLE = "bench_small: block on a foundation, n = 2, 1 + 10 increments"
BOXES_CONTACT = 'K = "calculix"\nstick_slope = "calculix"'
BOXES_OUTPUT = 'reactions = ["block_top", "foundation_bottom"]'


def prepare(name: str) -> Path:
    """Scene file, mesh and CalculiX deck of one scene in the work directory; the TOML."""
    from dolfinx_friction.reference import calculix
    from dolfinx_friction.scene.toml import load_scene
    d = B.work_dir("small") / name
    d.mkdir(parents=True, exist_ok=True)
    toml = d / f"{name}.toml"
    if name == "boxes":
        mesh = C.two_boxes_mesh(2)
        toml.write_text(block_on_foundation_toml(
            str(mesh), title=BOXES_TITLE, E=C.E, nu=C.NU, mu=C.MU, press=-C.PRESS, slide=C.SLIDE,
            slide_increments=10, contact=BOXES_CONTACT, output=BOXES_OUTPUT))
    else:
        for suffix in (".toml", ".msh"):
            shutil.copy(B.DEMOS / f"{name}{suffix}", d / f"{name}{suffix}")
    calculix.write_inp(load_scene(toml), d / f"{name}.inp")
    return toml


def timed(cmd: list[str], cwd: Path, env: dict) -> tuple[float, float]:
    """(wall, CPU) seconds of one command."""
    w0, c0 = time.perf_counter(), B.children_cpu()
    subprocess.run(cmd, cwd=cwd, env=env, check=True, capture_output=True)
    return time.perf_counter() - w0, B.children_cpu() - c0


def measure(name: str, repeats: int) -> dict:
    from dolfinx_friction.reference import calculix
    toml = prepare(name)
    d, py = toml.parent, B.PYTHON
    cold_cache = B.work_dir("small") / "mesh_cache_cold"
    env = dict(os.environ, PYTHONPATH=str(B.ROOT), OMP_NUM_THREADS="1",
               DOLFINX_FRICTION_CACHE=str(B.work_dir("small") / "mesh_cache"))
    ccx_env = dict(env, CCX_NPROC_STIFFNESS="1", CCX_NPROC_EQUATION_SOLVER="1",
                   CCX_NPROC_RESULTS="1")
    run = [py, "-m", "dolfinx_friction", "run", toml.name, "--quiet", "--out", "out"]
    commands = {
        "ours": (run, env),
        "ours, no fields": (run + ["--set", "output.fields=false"], env),
        "ours, cold mesh cache": (run, dict(env, DOLFINX_FRICTION_CACHE=str(cold_cache))),
        "ccx": ([calculix.ccx_executable(), "-i", name], ccx_env),
        "python -c pass": ([py, "-c", "pass"], env),
        "import dolfinx_friction.scene.runner": ([py, "-c", "import dolfinx_friction.scene.runner"], env),
    }
    times: dict[str, list] = {k: [] for k in commands}
    load0 = B.load_average()
    for _ in range(repeats):
        for key, (cmd, e) in commands.items():
            shutil.rmtree(d / "out", ignore_errors=True)
            shutil.rmtree(cold_cache, ignore_errors=True)
            times[key].append(timed(cmd, d, e))
    timed(run, d, env)  # once more with all outputs, for its summary
    summary = json.loads((d / "out" / "summary.json").read_text())
    return {"scene": name, "dofs": summary["dofs"], "newton": summary["newton_iterations"],
            "increments": summary["increments"], "phases": summary["wall_time_per_phase_s"],
            "run_wall": summary["wall_time_s"], "load": [load0, B.load_average()],
            "wall": {k: min(w for w, _ in v) for k, v in times.items()},
            "cpu": {k: min(c for _, c in v) for k, v in times.items()}}


def report(rows: list[dict], machine: dict, repeats: int) -> str:
    table = []
    for r in rows:
        ccx_w, ccx_c = r["wall"]["ccx"], r["cpu"]["ccx"]
        for key in r["wall"]:
            ratio = (f"{r['wall'][key] / ccx_w:.2f} / {r['cpu'][key] / ccx_c:.2f}"
                     if key.startswith("ours") else "")
            table.append([f"{r['scene']} ({r['dofs']:,} dofs)", key, f"{r['wall'][key]:.2f}",
                          f"{r['cpu'][key]:.2f}", ratio])
    split = []
    for r in rows:
        p = r["phases"]
        newton = sum(p.get(k, 0.0) for k in ("contact_search", "contact_assembly",
                                             "bulk_assembly", "linear_solve"))
        split.append([r["scene"], f"{r['wall']['import dolfinx_friction.scene.runner']:.2f}",
                      f"{p.get('setup', 0.0):.2f}", f"{newton:.2f}",
                      f"{p.get('output', 0.0):.2f}", f"{r['run_wall']:.2f}",
                      f"{r['newton']}"])
    loads = ", ".join(f"{r['scene']}: {r['load'][0]:.1f} -> {r['load'][1]:.1f}" for r in rows)
    return (B.machine_line(machine) + f"; load average per scene {loads}.\n\n"
            f"Minimum over {repeats} runs of each command (a fresh process each), seconds:\n\n"
            + B.table(["scene", "command", "wall", "CPU", "ours / ccx (wall / CPU)"], table)
            + "\n\nWhere our wall time goes (one more run with all outputs; `summary.json`'s "
            "phases, and the import floor measured alone), seconds:\n\n"
            + B.table(["scene", "interpreter + imports", "set-up (mesh, spaces, forms)",
                       "Newton (search, assembly, solve)", "output", "run() in all",
                       "Newton its"], split))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-results", action="store_true")
    args = ap.parse_args(argv)
    names = [s for s in args.scenes.split(",") if s]
    unknown = sorted(set(names) - set(SCENES))
    if unknown:
        ap.error(f"--scenes: unknown {unknown}; choose from {list(SCENES)}")
    machine = B.machine()
    rows = []
    for name in names:
        rows.append(measure(name, args.repeats))
        print(json.dumps(rows[-1]), flush=True)
    text = report(rows, machine, args.repeats)
    print(text)
    if not args.no_results:
        B.write_section("Small scenes: start-up and per-call cost", text)


if __name__ == "__main__":
    sys.exit(main())
