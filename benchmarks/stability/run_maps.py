"""Stability maps of the contact solver: where each method converges, needs cutbacks or fails.

    python benchmarks/stability/run_maps.py --quick      # < 5 min on 2 cores: the core maps
    python benchmarks/stability/run_maps.py              # every sweep and method (~1 h)

Options: ``--workers N`` (2), ``--only NAME`` (repeatable: a sweep's name, see
``SWEEPS``), ``--rerun`` (ignore cached cases), ``--plot-only`` (redraw from the cached
data).  Each sweep runs many tiny scenes (``_scenes.py``) in a ``multiprocessing`` pool
of at most ``--workers`` processes, one case per task, each with a time limit.

Outputs: ``figures/map_<sweep>.png`` (2D maps: one panel per method, cells coloured by
outcome and annotated with iterations), ``figures/sweep_<sweep>.png`` (1D sweeps:
Newton iterations and accuracy against the parameter), ``RESULTS.md`` (tables, machine,
date) and ``data/<sweep>.json`` (every case with its outcome, reused by ``--plot-only``
and by later runs unless ``--rerun``).  ``--quick`` writes ``figures/quick/`` and
``RESULTS-quick.md`` instead, so that it never overwrites the full results; its cases are
a subset of the full run's, so after a full run it only redraws (``--rerun`` to time it).
"""
from __future__ import annotations

import argparse
import datetime
import json
import math
import multiprocessing as mp
import os
import platform
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

HERE = Path(__file__).resolve().parent
FIGURES = HERE / "figures"
DATA = HERE / "data"
RESULTS = HERE / "RESULTS.md"
CASE_TIMEOUT = 150  # seconds per case (--quick: 40)

# ------------------------------------------------------------------------------ methods
#: solver variants compared in the maps
METHODS = {
    "exact": {},
    "exact + LS": {"line_search": True},
    "CalculiX tangent": {"tangent": "calculix"},
    "CalculiX + LS": {"tangent": "calculix", "line_search": True},
    "exact, freeze at 2": {"pairing": 2},
    "exact, no freeze": {"pairing": "never"},
    # augmented Lagrangian (Uzawa updates of the multipliers to 1e-4 of the spacing)
    "augmented": {"contact_method": "augmented"},
    "augmented + LS": {"contact_method": "augmented", "line_search": True},
    # the package's default stick slope (the maps' cases without ``lam``: CalculiX's E/2)
    "exact + LS, stick 1 E/h": {"line_search": True, "lam": 1.0},
    "augmented + LS, stick 1 E/h": {"contact_method": "augmented", "line_search": True,
                                    "lam": 1.0},
}
AUGMENTED = ["augmented", "augmented + LS"]
QUICK_METHODS = ["exact", "exact + LS"]
SWEEP_METHODS = ["exact", "exact + LS", "CalculiX tangent", "exact, no freeze"]

K_VALUES = [1e-2, 1e-1, 1.0, 10.0, 100.0, 1e3, 1e4]
K_QUICK = [1e-2, 1.0, 10.0, 100.0, 1e4]


@dataclass
class Sweep:
    """A 1D or 2D sweep of one scene family over case parameters, for several methods."""

    name: str
    family: str
    title: str
    x: tuple  # (key, values, label, log-scale?)
    y: tuple | None = None  # same, for a 2D map
    fixed: dict = field(default_factory=dict)
    methods: list = field(default_factory=lambda: list(METHODS))
    quick: dict | None = None  # overrides in --quick mode: x/y values, methods; None: skip
    #: what the cells / the second panel show, see ACCURACY: a key, or several keys (the
    #: maps' cells show each; the 1D sweeps' panel the first)
    accuracy: str | tuple = "pen"
    note: str = ""

    def axes(self, quick: bool):
        x, y, methods = self.x, self.y, self.methods
        if quick and self.quick:
            q = self.quick
            x = (x[0], q.get("x", x[1]), *x[2:])
            if y is not None:
                y = (y[0], q.get("y", y[1]), *y[2:])
            methods = q.get("methods", methods)
        return x, y, methods

    @property
    def measures(self) -> tuple:
        return (self.accuracy,) if isinstance(self.accuracy, str) else tuple(self.accuracy)

    def label(self) -> str:
        return "; ".join(ACCURACY[m][0] for m in self.measures)

    def cases(self, quick: bool) -> list[dict]:
        x, y, methods = self.axes(quick)
        out = []
        for m in methods:
            for yv in (y[1] if y else [None]):
                for xv in x[1]:
                    c = dict(family=self.family, **self.fixed, **METHODS[m], method=m)
                    c[x[0]] = xv
                    if y:
                        c[y[0]] = yv
                    out.append(c)
        return out


def _rel(a, b):
    return abs(a / b - 1.0) if (a is not None and b) else None


#: accuracy measures: (label, function(case result) -> value or None, text format)
ACCURACY = {
    "pen": ("largest overclosure / slave spacing", lambda r: r.get("penetration"),
            lambda v: f"{100 * v:.2g}%"),
    "ratio": ("|Ft/Fn - mu| / mu", lambda r: _rel(r.get("ratio"), r.get("mu", 0.3))
              if r.get("mu", 0.3) > 0 else None, lambda v: f"{100 * v:.2g}%"),
    "hertz": ("|p_max / p0(Hertz) - 1|", lambda r: _rel(r.get("p_max"), r.get("p0_hertz")),
              lambda v: f"{100 * v:.2g}%"),
    "Fn_osc": ("range of Fn / mean Fn (2nd half of the drag)", lambda r: r.get("Fn_osc"),
               lambda v: f"{100 * v:.2g}%"),
    "Fn": ("|Fn / Fn(reference) - 1|", lambda r: r.get("Fn_err"), lambda v: f"{100 * v:.2g}%"),
}

SLIDES = [0.125, 0.25, 0.5, 1.0, 2.0]
TANGENTS_LS = ["exact", "exact + LS", "CalculiX tangent", "CalculiX + LS"]
SWEEPS = [
    # --- penalty x increment size, every method
    Sweep("block_K_increment", "block",
          "sliding block (2D): penalty K x slide per increment",
          x=("k", K_VALUES, "K / (E/h)", True),
          y=("slide_faces", SLIDES, "slide per increment / master face", True),
          quick=dict(x=K_QUICK, y=[0.5, 1.0], methods=QUICK_METHODS)),
    Sweep("hertz_K_increment", "hertz",
          "Hertz cylinder (demo, coarse): penalty K x increments of the press",
          x=("k", K_VALUES, "K / (E/h)", True),
          y=("increments", [1, 2, 4, 8], "increments (press 0.25)", True),
          accuracy=("hertz", "pen"), methods=TANGENTS_LS + ["exact, no freeze"] + AUGMENTED,
          quick=dict(x=K_QUICK, y=[1, 4], methods=["exact"])),
    Sweep("ironing_K_increment", "ironing",
          "ironing (demo, coarse): penalty K x drag per increment",
          x=("k", K_VALUES, "K / (E/h)", True),
          y=("slide_faces", [0.25, 0.5, 1.0, 2.0], "drag per increment / master face", True),
          accuracy=("Fn_osc", "pen"), methods=list(METHODS)[:8],
          quick=dict(x=K_QUICK, y=[0.5, 1.0], methods=QUICK_METHODS)),
    Sweep("block3d_K_increment", "block3d",
          "sliding block (3D demo, coarse): penalty K x slide increments",
          x=("k", [1e-2, 1e-1, 1.0, 10.0, 100.0, 1e3], "K / (E/h)", True),
          y=("increments", [5, 10, 20], "increments (slide 10 = 1.5 block faces)", True),
          methods=["exact", "exact + LS", "CalculiX tangent"]),
    # --- friction: stick slope x mu
    Sweep("block_stick_mu", "block", "sliding block (2D): stick slope x friction coefficient",
          x=("lam", [1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0], "stick slope / (E/h)", True),
          y=("mu", [0.0, 0.1, 0.3, 0.6, 1.0], "mu", False),
          fixed=dict(slide_faces=0.25), accuracy="ratio",
          methods=["exact", "exact + LS", "CalculiX tangent", "augmented + LS"],
          quick=dict(x=[1e-3, 1e-1, 10.0], y=[0.0, 0.3, 1.0], methods=["exact"])),
    Sweep("ironing_stick_mu", "ironing", "ironing (demo): stick slope x friction coefficient",
          x=("lam", [1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0], "stick slope / (E/h)", True),
          y=("mu", [0.0, 0.1, 0.3, 0.6, 1.0], "mu", False),
          fixed=dict(slide_faces=0.5), accuracy="ratio",
          methods=["exact", "exact + LS", "CalculiX tangent"]),
    # --- pairing freeze
    Sweep("block_pairing", "block",
          "sliding block (2D): pairing iterations x slide per increment",
          x=("pairing", [1, 2, 4, 8, "never"], "pairing iterations (then frozen)", False),
          y=("slide_faces", [0.25, 0.5, 1.0, 2.0], "slide per increment / master face", True),
          methods=["exact", "exact + LS"], accuracy="ratio",
          quick=dict(y=[0.25, 1.0], methods=["exact"])),
    Sweep("ironing_pairing", "ironing",
          "ironing (demo): pairing iterations x drag per increment",
          x=("pairing", [1, 2, 4, 8, "never"], "pairing iterations (then frozen)", False),
          y=("slide_faces", [0.25, 0.5, 1.0, 2.0], "drag per increment / master face", True),
          methods=["exact", "exact + LS"], accuracy="Fn_osc",
          quick=dict(y=[0.5], methods=["exact"])),
    Sweep("groove_pairing", "groove",
          "tip in a V-groove (2D): pairing iterations x penalty K (face chattering)",
          x=("pairing", [1, 2, 4, 8, "never"], "pairing iterations (then frozen)", False),
          y=("k", [0.1, 1.0, 10.0, 100.0, 1e3], "K / (E/h)", True),
          methods=["exact", "exact + LS", "CalculiX tangent"],
          quick=dict(y=[1.0, 100.0], methods=["exact"])),
    # --- 1D sweeps
    Sweep("block_ratio", "block", "sliding block (2D): slave / master mesh size",
          x=("ratio", [0.25, 0.5, 1.0, 2.0, 4.0], "h_slave / h_master", True),
          fixed=dict(slide_faces=0.25), accuracy="ratio", methods=SWEEP_METHODS,
          quick=dict(methods=["exact"])),
    Sweep("hertz_ratio", "hertz", "Hertz cylinder (demo): slave / master mesh size",
          x=("ratio", [0.25, 0.5, 1.0, 2.0, 4.0], "h_slave / h_master", True),
          accuracy="hertz", methods=SWEEP_METHODS),
    Sweep("block_overhang", "block", "sliding block (2D): sliding off the end of the master",
          x=("overhang", [-0.25, 0.0, 0.125, 0.25, 0.5, 0.75],
             "block past the end of the master / block width", False),
          fixed=dict(slide_faces=0.25), accuracy="ratio", methods=SWEEP_METHODS,
          quick=dict(methods=["exact"])),
    Sweep("block_gap", "block", "sliding block (2D): initial gap (+) or penetration (-)",
          x=("gap", [-1.0, -0.5, -0.1, 0.0, 0.1, 0.5, 1.0], "initial gap / slave spacing", False),
          fixed=dict(slide_faces=0.25), accuracy="Fn", methods=SWEEP_METHODS,
          quick=dict(methods=["exact"])),
    Sweep("block_gap_ramp", "block",
          "sliding block (2D): initial gap / penetration, press in 4 increments",
          x=("gap", [-1.0, -0.5, -0.1, 0.0, 0.1, 0.5, 1.0], "initial gap / slave spacing", False),
          fixed=dict(slide_faces=0.25, press_increments=4), accuracy="pen",
          methods=["exact"]),
    Sweep("block_mu", "block", "sliding block (2D): friction coefficient",
          x=("mu", [0.0, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0], "mu", False),
          fixed=dict(slide_faces=0.25), accuracy="ratio", methods=SWEEP_METHODS),
    Sweep("ironing_mu", "ironing", "ironing (demo): friction coefficient",
          x=("mu", [0.0, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0], "mu", False),
          fixed=dict(slide_faces=0.5), accuracy="ratio", methods=SWEEP_METHODS),
]


# ------------------------------------------------------------------------------ running
class _Timeout(Exception):
    pass


def _alarm(signum, frame):
    raise _Timeout(f"case exceeded {CASE_TIMEOUT} s")


def _init_worker(timeout: int):
    global CASE_TIMEOUT
    CASE_TIMEOUT = timeout
    sys.path.insert(0, str(HERE))
    signal.signal(signal.SIGALRM, _alarm)
    import _scenes  # noqa: F401  (dolfinx loads once per worker)


def _work(case: dict) -> dict:
    import _scenes
    signal.alarm(CASE_TIMEOUT)
    try:
        out = _scenes.run_case({k: v for k, v in case.items() if k != "method"})
    finally:
        signal.alarm(0)
    out["method"] = case.get("method")
    if out.get("status") == "error" and "_Timeout" in out.get("message", ""):
        out["status"] = "timeout"
    return out


def _key(case: dict) -> str:
    return json.dumps(case, sort_keys=True)


def run_sweeps(sweeps: list[Sweep], quick: bool, workers: int, rerun: bool) -> dict:
    """Run every case not cached yet; returns {sweep name: [results]}."""
    DATA.mkdir(exist_ok=True)
    todo, cached = [], {}
    for s in sweeps:
        path = DATA / f"{s.name}.json"
        # --rerun reruns this mode's cases; the other cached cases stay in data/ (a
        # --quick --rerun must not drop the full run's cases)
        old = {} if not path.exists() else {
            _key(r["case"]): r for r in json.loads(path.read_text())}
        cached[s.name] = old
        todo += [(s.name, c) for c in s.cases(quick) if rerun or _key(c) not in old]
    commit = _machine()["commit"]
    print(f"{len(todo)} cases to run on {workers} worker(s)", flush=True)
    t0 = time.perf_counter()
    new: dict[str, list] = {s.name: [] for s in sweeps}
    if todo:
        ctx = mp.get_context("spawn")  # no MPI/PETSc state inherited by fork
        with ctx.Pool(workers, initializer=_init_worker,
                      initargs=(40 if quick else CASE_TIMEOUT,)) as pool:
            it = pool.imap(_work, [c for _, c in todo], chunksize=1)
            for n, ((name, case), res) in enumerate(zip(todo, it), 1):
                res = {k: v for k, v in res.items() if k != "traceback" or res["status"] == "error"}
                res["commit"] = commit
                new[name].append({"case": case, "result": res})
                print(f"[{n}/{len(todo)} {time.perf_counter() - t0:5.0f} s] {name} "
                      f"{ {k: v for k, v in case.items() if k != 'family'} } -> {res['status']}"
                      f"{' LOST' if res.get('lost') else ''} ({res['wall']:.1f} s)", flush=True)
    out = {}
    for s in sweeps:
        merged = dict(cached[s.name])
        merged.update({_key(r["case"]): r for r in new[s.name]})
        (DATA / f"{s.name}.json").write_text(json.dumps(list(merged.values()), indent=0,
                                                        default=float))
        wanted = {_key(c) for c in s.cases(quick)}
        out[s.name] = [r for k, r in merged.items() if k in wanted]
    return out


# ----------------------------------------------------------------------------- outcomes
OUTCOMES = {  # display order, colour, legend
    "ok": ("#4daf4a", "converged"),
    "cutback": ("#ffd92f", "converged after cutbacks"),
    "lost": ("#984ea3", "accepted with the contact lost (wrong)"),
    "stalled": ("#ff7f00", "failed: residual stuck at round-off (tolerance)"),
    "updates": ("#f781bf", "failed: 25 multiplier updates short of the tolerance"),
    "failed": ("#e41a1c", "failed (after all cutbacks)"),
    "timeout": ("#999999", "time limit"),
    "error": ("#000000", "error (exception)"),
}


#: a failed run whose last residual is below this stalled at the round-off floor: the
#: iterate had converged, the stopping test could not see it (see README.md)
STALL = 1e-7


def last_residual(r: dict):
    import re
    m = re.search(r"last residual ([0-9.e+-]+)", r.get("message", ""))
    return float(m.group(1)) if m else None


#: the failure of an augmented Lagrangian increment whose solves converged but whose
#: multiplier updates did not reach the tolerance (nls/stepping.py)
UPDATES = "augmented Lagrangian updates did not bring"


def outcome(r: dict) -> str:
    s = r["status"]
    if s in ("ok", "cutback") and r.get("lost"):
        return "lost"
    if s == "failed" and UPDATES in r.get("message", ""):
        return "updates"
    if s == "failed" and (last_residual(r) or 1.0) < STALL:
        return "stalled"
    return s


FAILURES = ("failed", "stalled", "updates", "timeout", "error")


def cell_text(r: dict, measures: tuple) -> str:
    o = outcome(r)
    if o in FAILURES:
        t = r.get("t_reached")
        mark = {"stalled": f"x {last_residual(r):.0e}", "updates": "x upd"}.get(o, "x")
        return mark if t is None else f"{mark}\nt={t:.2g}"
    txt = f"{r['mean_iterations']:.1f}"
    if r.get("cutbacks"):
        txt += f" c{r['cutbacks']}"
    if o == "lost":
        return txt + "\nlost"
    for m in measures:
        _, f, fmt = ACCURACY[m]
        v = f(r)
        if v is not None:
            txt += "\n" + fmt(v)
    if r.get("warned"):
        txt += "*"
    if r.get("detached"):
        txt += f" off{r['detached']}"
    return txt


def _fmt_value(v) -> str:
    if isinstance(v, float):
        return f"{v:g}"
    return str(v)


# ----------------------------------------------------------------------------- charts
def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _figures(quick: bool) -> Path:
    d = FIGURES / "quick" if quick else FIGURES
    d.mkdir(parents=True, exist_ok=True)
    return d


def _legend_handles():
    from matplotlib.patches import Patch
    return [Patch(color=c, label=l) for c, l in OUTCOMES.values()]


def _reference(sweep: Sweep, results: list[dict]) -> None:
    """Fill ``Fn_err`` (gap sweep): the normal force against the zero-gap run of the same
    method (the final indentation is the same for every initial gap)."""
    if "Fn" not in sweep.measures:
        return
    ref = {}
    for r in results:
        c, res = r["case"], r["result"]
        if c.get(sweep.x[0]) == 0.0 and res.get("Fn"):
            ref[c["method"]] = res["Fn"]
    for r in results:
        res = r["result"]
        base = ref.get(r["case"]["method"])
        res["Fn_err"] = abs(res["Fn"] / base - 1.0) if base and res.get("Fn") else None


def plot_map(sweep: Sweep, results: list[dict], quick: bool) -> Path:
    import numpy as np
    from matplotlib.colors import ListedColormap
    plt = _plt()
    x, y, methods = sweep.axes(quick)
    methods = [m for m in methods if any(r["case"]["method"] == m for r in results)]
    ncol = min(3, len(methods))
    nrow = math.ceil(len(methods) / ncol)
    height = 3.0 * nrow + 1.4
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.6 * ncol, height), squeeze=False, dpi=110)
    order = list(OUTCOMES)
    cmap = ListedColormap([OUTCOMES[o][0] for o in order])
    index = {(r["case"]["method"], _key(r["case"][x[0]]), _key(r["case"][y[0]])): r["result"]
             for r in results}
    for ax, m in zip(axes.ravel(), methods):
        grid = np.full((len(y[1]), len(x[1])), np.nan)
        for j, yv in enumerate(y[1]):
            for i, xv in enumerate(x[1]):
                r = index.get((m, _key(xv), _key(yv)))
                if r is None:
                    continue
                o = outcome(r)
                grid[j, i] = order.index(o)
                dark = o in ("lost", "failed", "error")
                ax.text(i, j, cell_text(r, sweep.measures), ha="center", va="center",
                        fontsize=6.5, color="white" if dark else "black")
        grid = np.ma.masked_invalid(grid)
        ax.imshow(grid, cmap=cmap, vmin=-0.5, vmax=len(order) - 0.5, origin="lower",
                  aspect="auto")
        ax.set_xticks(range(len(x[1])), [_fmt_value(v) for v in x[1]], fontsize=7)
        ax.set_yticks(range(len(y[1])), [_fmt_value(v) for v in y[1]], fontsize=7)
        ax.set_xlabel(x[2], fontsize=8)
        ax.set_ylabel(y[2], fontsize=8)
        ax.set_title(m, fontsize=9)
    for ax in axes.ravel()[len(methods):]:
        ax.axis("off")
    label = sweep.label()
    fig.suptitle(f"{sweep.title}\ncell: Newton iterations per increment (mean), cN = N cutbacks"
                 f"\n2nd line: {label}; * = penetration warning; x: failed at load time t",
                 fontsize=8.5)
    per_row = 4
    fig.legend(handles=_legend_handles(), loc="lower center", ncol=per_row, fontsize=7,
               frameon=False)
    rows = math.ceil(len(OUTCOMES) / per_row)
    fig.subplots_adjust(left=0.3 / ncol, right=0.99, top=1 - 0.8 / height,
                        bottom=(0.7 + 0.18 * rows) / height, wspace=0.28, hspace=0.45)
    path = _figures(quick) / f"map_{sweep.name}.png"
    fig.savefig(path)
    plt.close(fig)
    return path


MARKERS = {"ok": "o", "cutback": "s", "lost": "D", "stalled": "P", "failed": "X", "timeout": "X",
           "error": "X", "updates": "X"}


def plot_sweep(sweep: Sweep, results: list[dict], quick: bool) -> Path:
    plt = _plt()
    x, _, methods = sweep.axes(quick)
    methods = [m for m in methods if any(r["case"]["method"] == m for r in results)]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.8), dpi=110)
    numeric = all(isinstance(v, (int, float)) for v in x[1])
    pos = {(_key(v)): (v if numeric else i) for i, v in enumerate(x[1])}
    _, f, _ = ACCURACY[sweep.measures[0]]
    for k, m in enumerate(methods):
        rs = sorted((r for r in results if r["case"]["method"] == m),
                    key=lambda r: x[1].index(r["case"][x[0]]))
        xs = [pos[_key(r["case"][x[0]])] for r in rs]
        its = [r["result"].get("newton", 0) or 0 for r in rs]
        line, = a1.plot(xs, its, "-", lw=1, alpha=0.6, label=m)
        for xv, it, r in zip(xs, its, rs):
            o = outcome(r["result"])
            a1.plot(xv, max(it, 1), MARKERS[o], color=OUTCOMES[o][0], mec=line.get_color(),
                    ms=7, mew=1.2)
            v = f(r["result"]) if o in ("ok", "cutback") else None
            if v is not None:
                a2.plot(xv, max(v, 1e-12), MARKERS[o], color=line.get_color(), ms=6)
        acc = [(xv, f(r["result"])) for xv, r in zip(xs, rs)
               if outcome(r["result"]) in ("ok", "cutback") and f(r["result"]) is not None]
        if acc:
            a2.plot([a for a, _ in acc], [max(b, 1e-12) for _, b in acc], "-",
                    color=line.get_color(), lw=1, alpha=0.6)
    for a in (a1, a2):
        if numeric and x[3]:
            a.set_xscale("log")
        if not numeric:
            a.set_xticks(range(len(x[1])), [_fmt_value(v) for v in x[1]])
        a.set_xlabel(x[2])
        a.grid(alpha=0.3)
    a1.set_yscale("log")
    a1.set_ylabel("Newton iterations, whole run (incl. cutbacks)")
    a1.legend(fontsize=7)
    a2.set_yscale("log")
    a2.set_ylabel(ACCURACY[sweep.measures[0]][0], fontsize=8)
    a2.set_title("accuracy where converged", fontsize=9)
    fig.suptitle(sweep.title, fontsize=10)
    fig.legend(handles=_legend_handles(), loc="lower center", ncol=4, fontsize=7,
               frameon=False)
    fig.tight_layout(rect=(0, 0.11, 1, 0.95))
    path = _figures(quick) / f"sweep_{sweep.name}.png"
    fig.savefig(path)
    plt.close(fig)
    return path


# ----------------------------------------------------------------------------- RESULTS.md
def _machine() -> dict:
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import subprocess
    root = HERE.parent.parent
    try:
        commit = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain",
                                "dolfinx_friction"], capture_output=True, text=True).stdout.strip()
        commit += " + local changes to dolfinx_friction/" if dirty else ""
    except OSError:
        commit = "unknown"
    return dict(nproc=os.cpu_count(), cpu=cpu, python=platform.python_version(),
                date=datetime.datetime.now().strftime("%Y-%m-%d %H:%M"),
                load=round(os.getloadavg()[0], 1), commit=commit)


def table(sweep: Sweep, results: list[dict], quick: bool) -> str:
    x, y, methods = sweep.axes(quick)
    methods = [m for m in methods if any(r["case"]["method"] == m for r in results)]
    index = {(r["case"]["method"], _key(r["case"][x[0]]),
              _key(r["case"][y[0]]) if y else None): r["result"] for r in results}

    def cell(r):
        if r is None:
            return ""
        o = outcome(r)
        if o in FAILURES:
            t = r.get("t_reached")
            name = {"stalled": f"STALLED {last_residual(r):.0e}",
                    "updates": "FAILED (updates)"}.get(o, "FAILED")
            return f"**{name}**" + (f" (t={t:.3g})" if t is not None else "")
        txt = cell_text(r, sweep.measures).replace("\n", " ")
        return ("**LOST** " + txt[:-len(" lost")]) if o == "lost" else txt

    lines = []
    if y is None:
        lines.append(f"| {x[2]} | " + " | ".join(methods) + " |")
        lines.append("|---:|" + "---|" * len(methods))
        for xv in x[1]:
            lines.append(f"| {_fmt_value(xv)} | " + " | ".join(
                cell(index.get((m, _key(xv), None))) for m in methods) + " |")
    else:
        for m in methods:
            lines.append(f"\n*{m}* (rows: {y[2]}; columns: {x[2]})\n")
            lines.append("| | " + " | ".join(_fmt_value(v) for v in x[1]) + " |")
            lines.append("|---:|" + "---|" * len(x[1]))
            for yv in y[1]:
                lines.append(f"| {_fmt_value(yv)} | " + " | ".join(
                    cell(index.get((m, _key(xv), _key(yv)))) for xv in x[1]) + " |")
    return "\n".join(lines)


def counts(results: list[dict]) -> str:
    c: dict = {}
    for r in results:
        o = outcome(r["result"])
        c[o] = c.get(o, 0) + 1
    order = list(OUTCOMES)
    return ", ".join(f"{n} {o}" for o, n in sorted(c.items(), key=lambda t: order.index(t[0])))


def commits(results: list[dict]) -> str:
    """The package commits the runs were made at (older cached runs carry none)."""
    c: dict = {}
    for r in results:
        k = r["result"].get("commit", "68f56e6 (the full run)")
        c[k] = c.get(k, 0) + 1
    return ", ".join(f"{n} at {k}" for k, n in c.items())


def _results(quick: bool) -> Path:
    return RESULTS.with_name("RESULTS-quick.md") if quick else RESULTS


def write_results(sweeps, results, quick: bool, machine: dict, wall: float, figures) -> None:
    mode = "--quick" if quick else "full"
    parts = [
        "# Stability maps: results",
        "",
        f"Generated by `python benchmarks/stability/run_maps.py{' --quick' if quick else ''}` "
        f"({mode} mode) on {machine['date']}; {wall:.0f} s wall with {machine['workers']} "
        f"worker process(es).",
        "",
        f"* machine: {machine['nproc']} cores (nproc), CPU `{machine['cpu']}`, Python "
        f"{machine['python']}; 1-min load average {machine['load']} at the start (the machine "
        f"is shared with other jobs, so wall times are indicative only)",
        f"* package: git commit {machine.get('commit', 'unknown')} (the maps describe the "
        f"solver as of that commit); a sweep rerun since (`--only`) names its runs' commits "
        f"in its first line",
        "* what the findings mean, and where each method stops working: `README.md`",
        "",
        "Cell legend: `4.2 c3` = converged with 4.2 Newton iterations per converged increment on "
        "average and 3 cutbacks in the whole run (each cutback is a failed attempt of up to 30 "
        "iterations; the solver grows the increment back after easy increments, so a size "
        "that fails can be retried, and N can exceed the 5 levels); the second number is the "
        "accuracy measure "
        "named above each table; `*` = the run printed the penetration warning (overclosure "
        "> 5 % of the slave spacing); `offN` = the run warned that N slave nodes in contact "
        "slid off the master surface (summed over increments); **FAILED (t=...)** = an increment still failed after "
        "5 successive halvings, `t` = the load-step time reached; **STALLED 1e-10 (t=...)** = "
        "failed the same way, but the last residual (here 1e-10) sits at the round-off floor: "
        "the iterate had converged and the stopping test could not see it; **FAILED "
        "(updates)** = an augmented Lagrangian increment still failed after the cutbacks "
        "because its solves converged but 25 multiplier updates did not bring the "
        "overclosure and the stick slip below the tolerance; LOST = the solver "
        "accepted "
        "an increment in which the contact carrying the load had vanished (no slave node "
        "in contact, or the normal force below 10 % of its value after the press): the run "
        "reports converged but the answer is wrong.",
        "",
        "Case defaults (see `_scenes.py`): Newton tolerance 1e-9 relative, at most 30 "
        "iterations, at most 5 cutbacks; K and the stick slope are given as multiples of "
        "E_slave / h_slave (the package default K = 50 E is 6.25 E/h for the 2D block, "
        "h = 1/8; 10 E/h for the Hertz mesh, h = 0.2; 25 E/h for the ironing block, h = 0.5; "
        "333 E/h for the coarse 3D block, h = 20/3); default stick slope E/2; mu = 0.3 (Hertz, "
        "groove: 0).",
        "",
    ]
    for s in sweeps:
        rs = results.get(s.name)
        if not rs:
            continue
        fig = figures.get(s.name)
        parts += [f"## {s.title}", "",
                  f"`{s.name}`: {len(rs)} runs ({counts(rs)}; {commits(rs)}). Accuracy: "
                  f"{s.label()}. Figure: "
                  f"`{fig.relative_to(HERE)}`" if fig else "", ""]
        if s.note:
            parts += [s.note, ""]
        parts += [table(s, rs, quick), ""]
    _results(quick).write_text("\n".join(parts) + "\n")


# ----------------------------------------------------------------------------- main
def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="the core maps only (< 5 min)")
    p.add_argument("--workers", type=int, default=2, help="parallel processes (default 2)")
    p.add_argument("--only", action="append", default=[], help="run only this sweep")
    p.add_argument("--rerun", action="store_true", help="ignore cached results")
    p.add_argument("--plot-only", action="store_true", help="redraw from data/*.json")
    args = p.parse_args(argv)
    sweeps = [s for s in SWEEPS if (not args.only or s.name in args.only)
              and (not args.quick or s.quick is not None)]
    machine = _machine()
    machine["workers"] = args.workers
    t0 = time.perf_counter()
    if args.plot_only:
        results = {}
        for s in sweeps:
            path = DATA / f"{s.name}.json"
            if path.exists():
                wanted = {_key(c) for c in s.cases(args.quick)}
                results[s.name] = [r for r in json.loads(path.read_text())
                                   if _key(r["case"]) in wanted]
    else:
        results = run_sweeps(sweeps, args.quick, max(1, min(args.workers, 2)), args.rerun)
    wall = time.perf_counter() - t0
    meta = DATA / f"_run{'_quick' if args.quick else ''}.json"
    if args.plot_only and meta.exists():
        machine, wall = json.loads(meta.read_text())
    elif not args.only and not args.plot_only:
        meta.write_text(json.dumps([machine, wall]))
    figures = {}
    for s in sweeps:
        rs = [dict(case=r["case"], result=dict(r["result"])) for r in results.get(s.name, [])]
        if not rs:
            continue
        _reference(s, rs)
        results[s.name] = rs
        figures[s.name] = plot_map(s, rs, args.quick) if s.y else plot_sweep(s, rs, args.quick)
        print(f"figure: {figures[s.name].relative_to(HERE.parent.parent)}  ({counts(rs)})")
    if not args.only:
        write_results(sweeps, results, args.quick, machine, wall, figures)
        print(f"written: {_results(args.quick).relative_to(HERE.parent.parent)} ({wall:.0f} s)")


if __name__ == "__main__":
    main()
