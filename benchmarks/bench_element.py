"""Throughput of the contact element, numpy vs compiled: residual + tangent per pair.

``face_kinematics`` + ``evaluate`` on Q4 master faces (warped, deformed), Coulomb
friction, every pair in slip, one core.  For 200, 10^3, 10^4 and 10^5 pairs in
one call (a contact zone of that many slave nodes, as ``ContactInteraction``
evaluates it), both implementations of contact/backend.py: CPU time per call
and pairs/s, timed interleaved (best of N).  Also: the stage split (projection,
rest of the kinematics, evaluation), the projection warm-started from the
previous iterate's ``xi``, the compile time of the numba kernels (first call
with an empty cache) and the first call of a second process that loads them
from numba's cache.  ``--write`` records the figures in benchmarks/RESULTS.md
under "Contact element throughput".

    .venv/bin/python benchmarks/bench_element.py [--quick] [--write]
"""
from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
             "BLIS_NUM_THREADS", "NUMEXPR_NUM_THREADS", "VECLIB_MAXIMUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import datetime  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from dolfinx_friction.contact import backend  # noqa: E402
from dolfinx_friction.contact.element import (  # noqa: E402
    SLIP,
    ContactParameters,
    evaluate,
    face_kinematics,
)
from dolfinx_friction.contact.friction import FrictionState  # noqa: E402
from dolfinx_friction.contact.laws import Linear  # noqa: E402
from dolfinx_friction.contact.projection import project  # noqa: E402
from dolfinx_friction.contact.shapes import FACE_TYPES, surface_vector  # noqa: E402

FACE = FACE_TYPES["Q4"]
PARAMS = ContactParameters(Linear(K=1e4, sigma_inf=3.0), mu=0.3, stick_slope=100.0)
SIZES = (200, 10**3, 10**4, 10**5)
BACKENDS = ("numpy", "numba")
TARGET = 5e5  # pairs/s on one core (issue 14)
RESULTS = Path(__file__).resolve().parent / "RESULTS.md"
HEADING = "## Contact element throughput"


def make_pairs(n: int, seed: int = 0):
    """n warped, deformed Q4 faces with a slave 0.01 below a random interior point, and a
    history that puts every pair in slip (|F_tr| = 2 mu |F_N|)."""
    rng = np.random.default_rng(seed)
    base = 0.5 * FACE.nodes  # basix order, side 1
    x_face = np.empty((n, 4, 3))
    x_face[:, :, :2] = base + 0.05 * rng.uniform(-1, 1, (n, 4, 2))
    x_face[:, :, 2] = 0.05 * rng.uniform(-1, 1, (n, 4))  # warped
    x_face += 10.0 * rng.uniform(-1, 1, (n, 1, 3))  # spread over a "mesh"
    u_face = 0.02 * rng.uniform(-1, 1, (n, 4, 3))
    xi = rng.uniform(-0.7, 0.7, (n, 2))
    phi, dphi, _ = FACE.evaluate(xi)
    q = np.einsum("nk,nkd->nd", phi, x_face)
    m = surface_vector(np.einsum("nka,nkd->nad", dphi, x_face))
    nrm = m / np.linalg.norm(m, axis=1)[:, None]
    p = q - 0.01 * nrm
    u_slave = 0.02 * rng.uniform(-1, 1, (n, 3))
    area = rng.uniform(0.2, 0.3, n)
    X_face, X_slave = x_face - u_face, p - u_slave
    kin = face_kinematics(FACE, X_slave, u_slave, X_face, u_face)
    F_N, _ = PARAMS.law.normal_force(kin.g_N, area)
    # history: s random, trial direction tangential, |F_tr| = 2 mu |F_N|
    s = 0.01 * rng.uniform(-1, 1, (n, 3))
    g_T_n = 0.01 * rng.uniform(-1, 1, (n, 3))
    s_N = np.einsum("nd,nd->n", s, kin.normal)
    g_T = g_T_n + s - s_N[:, None] * kin.normal
    t = rng.standard_normal((n, 3))
    t -= np.einsum("nd,nd->n", t, kin.normal)[:, None] * kin.normal
    t /= np.linalg.norm(t, axis=1)[:, None]
    K_t = PARAMS.stick_slope * area
    g_p = g_T - (2.0 * PARAMS.mu * np.abs(F_N) / K_t)[:, None] * t
    hist = FrictionState(kin.w - s, g_T_n, g_p)
    # the projection of a previous Newton iterate (slave moved by 1e-4): a warm start
    xi_prev = face_kinematics(FACE, X_slave, u_slave + 1e-4, X_face, u_face).xi
    return dict(X_slave=X_slave, u_slave=u_slave, X_face=X_face, u_face=u_face, area=area,
                hist=hist, xi_prev=xi_prev)


def run(data, n: int, warm: bool = False):
    """Residual + tangent of the first n pairs in one call (the timed work); ``warm``: the
    projection starts from the previous iterate's xi instead of the face centroid."""
    kin = face_kinematics(FACE, data["X_slave"][:n], data["u_slave"][:n], data["X_face"][:n],
                          data["u_face"][:n], xi0=data["xi_prev"][:n] if warm else None)
    return evaluate(kin, data["area"][:n], PARAMS, data["hist"].take(slice(0, n)))


def clock() -> float:
    """CPU time of this process: single-threaded work, so on an idle core it equals the wall
    time, and it is not inflated when other jobs time-share the machine."""
    return time.process_time()


def best_time(work, seconds: float, min_reps: int = 3) -> float:
    """Best CPU time of ``work()`` over repeats filling about ``seconds``."""
    best, spent, reps = np.inf, 0.0, 0
    while reps < min_reps or spent < seconds:
        t0 = clock()
        work()
        t = clock() - t0
        best, spent, reps = min(best, t), spent + t, reps + 1
    return best


def interleaved(cases: dict, rounds: int, seconds: float) -> dict:
    """Best time of each ``cases[key] = (choice, work)``, rounds interleaved so that load
    from other processes hits all cases alike."""
    best = {key: np.inf for key in cases}
    for _ in range(rounds):
        for key, (choice, work) in cases.items():
            with backend.use(choice):
                best[key] = min(best[key], best_time(work, seconds / rounds, 1))
    return best


def throughput(data, sizes) -> dict:
    """``{(choice, n): seconds per call}`` for one call of n pairs, cold projection start."""
    for c in BACKENDS:  # compile (or load) the kernels outside the timing
        with backend.use(c):
            assert np.all(run(data, 200).status == SLIP)
    out = {}
    for n in sizes:
        cases = {(c, n): (c, lambda n=n: run(data, n)) for c in BACKENDS}
        out.update(interleaved(cases, rounds=3, seconds=3.0))
    return out


def stages(data, n: int) -> dict:
    """``{(choice, stage): seconds}`` for n pairs: projection, face_kinematics (with the
    projection), evaluate, and the whole with a warm projection start."""
    x_s, x_f = data["X_slave"][:n] + data["u_slave"][:n], data["X_face"][:n] + data["u_face"][:n]
    args = (FACE, data["X_slave"][:n], data["u_slave"][:n], data["X_face"][:n],
            data["u_face"][:n])
    kin = face_kinematics(*args)
    hist = data["hist"].take(slice(0, n))
    work = {"project": lambda: project(FACE, x_s, x_f),
            "face_kinematics": lambda: face_kinematics(*args),
            "evaluate": lambda: evaluate(kin, data["area"][:n], PARAMS, hist),
            "total, cold start": lambda: run(data, n),
            "total, warm start": lambda: run(data, n, warm=True)}
    cases = {(c, s): (c, w) for c in BACKENDS for s, w in work.items()}
    return interleaved(cases, rounds=3, seconds=1.5)


_STARTUP = """
import json, sys, time
t0 = time.perf_counter()
from dolfinx_friction.contact import backend, kernels
t_import = time.perf_counter() - t0
sys.path.insert(0, {bench!r})
import bench_element as B
with backend.use("numpy"):  # set-up without touching the kernels
    data = B.make_pairs(200)
with backend.use("numba"):
    t0 = time.perf_counter(); B.run(data, 200); t_first = time.perf_counter() - t0
    t0 = time.perf_counter(); B.run(data, 200); t_second = time.perf_counter() - t0
    t0 = time.perf_counter()
    x = data["X_slave"] + data["u_slave"]
    B.project(B.FACE, x, data["X_face"] + data["u_face"])
    kin = kernels.rigid_kinematics("plane", data["X_slave"], data["u_slave"], [0.0, 0, 0],
                                   point=[0.0, 0, 0], normal=[0.0, 0, 1])
    kernels.evaluate(kin, data["area"], B.ContactParameters(B.PARAMS.law), None)
    t_rest = time.perf_counter() - t0
print(json.dumps(dict(t_import=t_import, t_first=t_first, t_second=t_second, t_rest=t_rest)))
"""


def startup() -> list[dict]:
    """Two fresh processes sharing an empty numba cache directory: the first compiles the
    kernels, the second loads them.  Wall seconds of: importing the kernels (numba), the first
    and second ``run`` of 200 pairs, and the first calls of the other entry points."""
    code = _STARTUP.format(bench=str(Path(__file__).resolve().parent))
    out = []
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache, PYTHONPATH=str(ROOT))
        for _ in range(2):
            res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                                 text=True, check=True)
            out.append(json.loads(res.stdout.strip().splitlines()[-1]))
    return out


def machine():
    cpu = "unknown"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        import numba
        numba_version = numba.__version__
    except ImportError:
        numba_version = "not installed"
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip() or "unknown"
    dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--",
                            "dolfinx_friction/contact", "benchmarks/bench_element.py"],
                           capture_output=True, text=True).stdout.strip()
    return dict(nproc=os.cpu_count(), cpu=cpu, numpy=np.__version__, numba=numba_version,
                python=platform.python_version(), memory=_memory(),
                commit=commit + (" (+ uncommitted changes)" if dirty else ""))


def _memory():
    try:
        for line in open("/proc/meminfo"):
            if line.startswith("MemTotal"):
                return f"{int(line.split()[1]) / 2**20:.0f} GiB"
    except OSError:
        pass
    return "unknown"


def write_results(text: str) -> None:
    """Replace (or append) this benchmark's section in RESULTS.md, leaving others intact."""
    old = RESULTS.read_text() if RESULTS.exists() else "# Benchmarks\n"
    start = old.find(HEADING)
    if start < 0:
        new = old.rstrip("\n") + "\n\n" + text
    else:
        end = old.find("\n## ", start + len(HEADING))
        new = old[:start] + text.rstrip("\n") + ("\n" if end < 0 else "\n\n" + old[end + 1:])
    RESULTS.write_text(new.rstrip("\n") + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="only up to 10^4 pairs")
    ap.add_argument("--write", action="store_true", help="record in benchmarks/RESULTS.md")
    args = ap.parse_args()
    if backend.compiled() is None:
        sys.exit("numba does not import here: nothing to compare")
    sizes = SIZES[:-1] if args.quick else SIZES
    info = machine()
    info["load_start"] = os.getloadavg()[0]
    info["date"] = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    print(f"machine: {info['nproc']} cores, {info['cpu']}; numpy {info['numpy']}, "
          f"numba {info['numba']}, Python {info['python']}; commit {info['commit']}; "
          f"load {info['load_start']:.1f}")

    start = startup()
    for label, s in zip(("empty cache", "cached"), start):
        print(f"{label}: import {s['t_import']:.2f} s, first run (200 pairs) "
              f"{s['t_first']:.2f} s, second {s['t_second'] * 1e3:.2f} ms, "
              f"other entry points {s['t_rest']:.2f} s")

    data = make_pairs(max(sizes))
    times = throughput(data, sizes)
    for n in sizes:
        tn, tc = times[("numpy", n)], times[("numba", n)]
        print(f"{n:>8d} pairs/call: numpy {tn * 1e3:9.2f} ms {n / tn:11,.0f}/s   numba "
              f"{tc * 1e3:8.3f} ms {n / tc:11,.0f}/s   {tn / tc:5.1f}x")
    n_st = min(10**4, max(sizes))
    split = stages(data, n_st)
    print(f"stages, {n_st} pairs [ns/pair]:")
    for stage in ("project", "face_kinematics", "evaluate", "total, cold start",
                  "total, warm start"):
        print(f"  {stage:<20s} numpy {split[('numpy', stage)] / n_st * 1e9:8.0f}   "
              f"numba {split[('numba', stage)] / n_st * 1e9:6.0f}")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    info["load_end"] = os.getloadavg()[0]
    print(f"peak RSS {rss:.0f} MiB, load at end {info['load_end']:.1f}")
    if args.write:
        write_results(_section(info, sizes, times, n_st, split, start, rss))
        print(f"wrote {RESULTS}")


def _section(info, sizes, times, n_st, split, start, rss) -> str:
    lines = [HEADING, "",
             f"`benchmarks/bench_element.py` ({info['date']}, commit {info['commit']}): "
             "residual + consistent tangent (`face_kinematics` + `evaluate`) of node-to-surface "
             "elements on warped, deformed Q4 master faces, linear law, Coulomb friction with "
             "every pair in slip, projection from the face centroid; n pairs in one call (a "
             "contact zone of n slave nodes); one core.  Both implementations of "
             "`contact/backend.py`: the numpy reference and the compiled numba kernels "
             "(`contact/kernels.py`, the default when numba imports).", "",
             f"* machine: {info['nproc']} cores (nproc), CPU `{info['cpu']}`, {info['memory']} "
             f"RAM; numpy {info['numpy']}, numba {info['numba']}, Python {info['python']}",
             f"* 1-min load average at start / end: {info['load_start']:.1f} / "
             f"{info['load_end']:.1f} on {info['nproc']} cores (other jobs shared the machine); "
             "times are best-of-N *CPU* times of the single-threaded process, the two "
             "implementations timed interleaved, so ratios are from one run under the same "
             "load", f"* peak RSS of the whole run: {rss:.0f} MiB", "",
             "| pairs per call | numpy [ms/call] | numpy [pairs/s] | numba [ms/call] | "
             "numba [pairs/s] | speed-up |", "|---:|---:|---:|---:|---:|---:|"]
    for n in sizes:
        tn, tc = times[("numpy", n)], times[("numba", n)]
        lines.append(f"| {n:,} | {tn * 1e3:.2f} | {n / tn:,.0f} | {tc * 1e3:.3f} | "
                     f"{n / tc:,.0f} | {tn / tc:.1f}x |")
    worst = min(n / times[("numba", n)] for n in sizes)
    lines += ["", f"Target: >= {TARGET:,.0f} pairs/s on one core.  Compiled: at least "
              f"{worst:,.0f} pairs/s at every size ({worst / TARGET:.2f}x the target), "
              f"{times[('numba', sizes[0])] * 1e6:.0f} us for a call of {sizes[0]} pairs "
              f"(numpy {times[('numpy', sizes[0])] * 1e3:.1f} ms: its per-call cost of ~60 "
              "numpy operations on stacks of tiny matrices dominates small contact zones)."]
    lines += ["", f"Stages on {n_st:,} pairs [ns per pair] (`project` is part of "
              "`face_kinematics`; warm start: the projection starts from the previous Newton "
              "iterate's xi, as `ContactInteraction.evaluate` passes it):", "",
              "| stage | numpy | numba | speed-up |", "|---|---:|---:|---:|"]
    for stage in ("project", "face_kinematics", "evaluate", "total, cold start",
                  "total, warm start"):
        tn, tc = split[("numpy", stage)], split[("numba", stage)]
        lines.append(f"| {stage} | {tn / n_st * 1e9:,.0f} | {tc / n_st * 1e9:,.0f} | "
                     f"{tn / tc:.1f}x |")
    cold, warm = start
    lines += ["", "Start-up (wall seconds, two fresh processes sharing an empty "
              "`NUMBA_CACHE_DIR`): the first compiles the kernels, the second loads them from "
              "numba's on-disk cache (`cache=True`; by default the cache lives in "
              "`dolfinx_friction/contact/__pycache__`, or the user's cache directory when that "
              "is not writable; with neither, the kernels compile in every process).", "",
              "| process | import numba + kernels | first call, 200 pairs (Q4 kinematics + "
              "evaluate) | second call | first calls of project, rigid kinematics, frictionless "
              "evaluate |", "|---|---:|---:|---:|---:|"]
    for label, s in (("first (empty cache: compiles)", cold), ("second (loads the cache)", warm)):
        lines.append(f"| {label} | {s['t_import']:.2f} s | {s['t_first']:.2f} s | "
                     f"{s['t_second'] * 1e3:.2f} ms | {s['t_rest']:.2f} s |")
    lines += ["", NOTES]
    return "\n".join(lines) + "\n"


NOTES = """\
How the kernels get there: one loop over pairs; per pair the projection (damped Newton with
projection.py's rules, the geometry of each accepted trial point reused for the next step and
for the kinematics), the kinematics and the element arrays, with the element dofs flattened so
that inner loops run over contiguous memory, 2x2 systems in closed form, and scratch arrays
allocated once per call.  The per-pair code passes whole batch arrays and the pair index,
never array views or tuples of arrays: numba reference-counts each of those with an atomic
operation, which took half of the time in a first version (3.5e5 pairs/s).  The numpy path
stays the reference (`*_numpy`, `DOLFINX_FRICTION_KERNELS=numpy`); `tests/contact/test_kernels.py`
checks both equal to 1e-12 relative over every face type, rigid shape, law, state and tangent
option."""


if __name__ == "__main__":
    main()
