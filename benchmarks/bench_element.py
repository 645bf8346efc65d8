"""Throughput of the contact element: residual + tangent (face_kinematics + evaluate).

Q4 master faces (warped, deformed), Coulomb friction, every pair in slip, on one
core.  Prints pairs/s for 10^3 .. 10^6 pairs, processed in chunks, and (with
--write) records the figures in benchmarks/RESULTS.md under "Contact element
throughput".  --profile breaks one chunk down by numpy call site (which einsum,
solve, eigvalsh dominates).

    PYTHONPATH=. /usr/bin/python3 benchmarks/bench_element.py [--quick] [--profile] [--write]
"""
from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
             "BLIS_NUM_THREADS", "NUMEXPR_NUM_THREADS", "VECLIB_MAXIMUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import datetime  # noqa: E402
import platform  # noqa: E402
import resource  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections import defaultdict  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from dolfinx_friction.contact import element as element_mod  # noqa: E402
from dolfinx_friction.contact.element import (  # noqa: E402
    SLIP,
    ContactParameters,
    evaluate,
    face_kinematics,
)
from dolfinx_friction.contact.friction import FrictionState  # noqa: E402
from dolfinx_friction.contact.laws import Linear  # noqa: E402
from dolfinx_friction.contact.shapes import FACE_TYPES, surface_vector  # noqa: E402

FACE = FACE_TYPES["Q4"]
PARAMS = ContactParameters(Linear(K=1e4, sigma_inf=3.0), mu=0.3, stick_slope=100.0)
SIZES = (10**3, 10**4, 10**5, 10**6)
CHUNKS = (10**3, 4 * 10**3, 10**4, 3 * 10**4, 10**5)
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
    # history: s random, trial direction tangential, |F_tr| = 2 mu |F_N|
    hist = FrictionState.zeros(n, 3)
    xi_prev = np.empty((n, 2))
    for lo in range(0, n, 50_000):  # in chunks: evaluation peaks at ~6 kB per pair
        sl = slice(lo, min(lo + 50_000, n))
        m_ = sl.stop - sl.start
        kin = face_kinematics(FACE, X_slave[sl], u_slave[sl], X_face[sl], u_face[sl])
        F_N, _ = PARAMS.law.normal_force(kin.g_N, area[sl])
        s = 0.01 * rng.uniform(-1, 1, (m_, 3))
        g_T_n = 0.01 * rng.uniform(-1, 1, (m_, 3))
        s_N = np.einsum("nd,nd->n", s, kin.normal)
        g_T = g_T_n + s - s_N[:, None] * kin.normal
        t = rng.standard_normal((m_, 3))
        t -= np.einsum("nd,nd->n", t, kin.normal)[:, None] * kin.normal
        t /= np.linalg.norm(t, axis=1)[:, None]
        K_t = PARAMS.stick_slope * area[sl]
        g_p = g_T - (2.0 * PARAMS.mu * np.abs(F_N) / K_t)[:, None] * t
        hist.w[sl], hist.g_T[sl], hist.g_p[sl] = kin.w - s, g_T_n, g_p
        # the projection of a previous Newton iterate (slave moved by 1e-4): a warm start
        xi_prev[sl] = face_kinematics(FACE, X_slave[sl], u_slave[sl] + 1e-4, X_face[sl],
                                      u_face[sl]).xi
    return dict(X_slave=X_slave, u_slave=u_slave, X_face=X_face, u_face=u_face, area=area,
                hist=hist, xi_prev=xi_prev)


def run(data, lo: int, hi: int, warm: bool = False):
    """Residual + tangent of pairs lo:hi (the timed work); ``warm``: the projection starts
    from the previous iterate's xi instead of the face centroid."""
    kin = face_kinematics(FACE, data["X_slave"][lo:hi], data["u_slave"][lo:hi],
                          data["X_face"][lo:hi], data["u_face"][lo:hi],
                          xi0=data["xi_prev"][lo:hi] if warm else None)
    return evaluate(kin, data["area"][lo:hi], PARAMS, data["hist"].take(slice(lo, hi)))


def clock() -> float:
    """CPU time of this process: single-threaded work, so on an idle core it equals the wall
    time, and it is not inflated when other jobs time-share the machine."""
    return time.process_time()


def time_pairs(data, n: int, chunk: int, repeats: int, warm: bool = False) -> float:
    """Best CPU time over ``repeats`` for the first n pairs in chunks of ``chunk``."""
    best = np.inf
    for _ in range(repeats):
        t0 = clock()
        for lo in range(0, n, chunk):
            run(data, lo, min(lo + chunk, n), warm)
        best = min(best, clock() - t0)
    return best


class _Profiler:
    """Wrap numpy's einsum / solve / eigvalsh / cross / norm to time them per call site."""

    def __init__(self):
        self.times = defaultdict(float)
        self.calls = defaultdict(int)
        self._saved = []

    def _wrap(self, owner, name, label):
        orig = getattr(owner, name)

        def wrapper(*args, **kwargs):
            frame = sys._getframe(1)
            where = f"{Path(frame.f_code.co_filename).name}:{frame.f_lineno}"
            key = f"{label}({args[0]!r})" if label == "einsum" else label
            t0 = clock()
            out = orig(*args, **kwargs)
            self.times[(where, key)] += clock() - t0
            self.calls[(where, key)] += 1
            return out

        self._saved.append((owner, name, orig))
        setattr(owner, name, wrapper)

    def __enter__(self):
        self._wrap(np, "einsum", "einsum")
        self._wrap(np.linalg, "solve", "linalg.solve")
        self._wrap(np.linalg, "eigvalsh", "linalg.eigvalsh")
        self._wrap(np.linalg, "norm", "linalg.norm")
        self._wrap(np, "cross", "cross")
        return self

    def __exit__(self, *exc):
        for owner, name, orig in reversed(self._saved):
            setattr(owner, name, orig)


def profile(data, chunk: int):
    import dolfinx_friction.contact.projection as projection_mod

    t0 = clock()
    run(data, 0, chunk)
    total = clock() - t0
    t0 = clock()
    with _Profiler() as prof:
        run(data, 0, chunk)
    total_prof = clock() - t0
    # stage split: projection vs the rest of face_kinematics vs evaluate
    t0 = clock()
    x_s = data["X_slave"][:chunk] + data["u_slave"][:chunk]
    x_f = data["X_face"][:chunk] + data["u_face"][:chunk]
    pr = projection_mod.project(FACE, x_s, x_f)
    t_proj = clock() - t0
    t0 = clock()
    kin = face_kinematics(FACE, data["X_slave"][:chunk], data["u_slave"][:chunk],
                          data["X_face"][:chunk], data["u_face"][:chunk])
    t_kin = clock() - t0
    t0 = clock()
    res = evaluate(kin, data["area"][:chunk], PARAMS, data["hist"].take(slice(0, chunk)))
    t_eval = clock() - t0
    assert np.all(res.status == SLIP)
    iters = _newton_iterations(data, chunk)
    iters_warm = _newton_iterations(data, chunk, warm=True)
    rows = sorted(prof.times.items(), key=lambda kv: -kv[1])
    return dict(total=total, total_prof=total_prof, t_proj=t_proj, t_kin=t_kin, t_eval=t_eval,
                rows=[(w, k, t, prof.calls[(w, k)]) for (w, k), t in rows], iters=iters,
                iters_warm=iters_warm,
                interior=bool(pr.interior.all()))


def _newton_iterations(data, chunk, warm=False):
    """Number of Newton sweeps project() makes on this chunk (counts _newton_step calls)."""
    import dolfinx_friction.contact.projection as projection_mod

    count = [0]
    orig = projection_mod._newton_step

    def counting(*a, **k):
        count[0] += 1
        return orig(*a, **k)

    projection_mod._newton_step = counting
    try:
        x_s = data["X_slave"][:chunk] + data["u_slave"][:chunk]
        x_f = data["X_face"][:chunk] + data["u_face"][:chunk]
        projection_mod.project(FACE, x_s, x_f, data["xi_prev"][:chunk] if warm else None)
    finally:
        projection_mod._newton_step = orig
    return count[0]


# ----------------------------------------------------------------------------- what-if
# Same maths, cheaper kernels: the contact modules' ``np`` is swapped for a proxy whose
# einsum maps the subscripts used there onto batched matmul / broadcasting, and whose
# 2x2 eigvalsh / solve are closed forms.  Measures what such a rewrite of element.py /
# projection.py would gain, without touching them (restored on exit).
def _mm_einsum(sub, *ops, **kw):
    mm = np.matmul
    a = ops[0]
    n = len(a)
    if sub == "nka,nkd->nad":
        return mm(a.transpose(0, 2, 1), ops[1])
    if sub == "nkab,nkd->nabd":
        k, p_, q_ = a.shape[1:]
        return mm(a.reshape(n, k, p_ * q_).transpose(0, 2, 1), ops[1]).reshape(n, p_, q_, -1)
    if sub == "nk,nkd->nd":
        return mm(a[:, None], ops[1])[:, 0]
    if sub in ("nd,nd->n", "nad,nad->n"):
        return (a * ops[1]).reshape(n, -1).sum(axis=1)
    if sub in ("nak,nail->nkil",):
        b = ops[1]
        return mm(a.transpose(0, 2, 1), b.reshape(n, b.shape[1], -1)).reshape(
            n, a.shape[2], *b.shape[2:])
    if sub == "nkc,ncil->nkil":
        b = ops[1]
        return mm(a, b.reshape(n, b.shape[1], -1)).reshape(n, a.shape[1], *b.shape[2:])
    if sub == "nd,nad->na":
        return mm(ops[1], a[:, :, None])[..., 0]
    if sub == "nad,nbd->nab":
        return mm(a, ops[1].transpose(0, 2, 1))
    if sub in ("nk,nkil->nil", "nc,ncil->nil", "nc,ncid->nid"):
        b = ops[1]
        return mm(a[:, None], b.reshape(n, b.shape[1], -1)).reshape(n, *b.shape[2:])
    if sub == "nk,ncil->nkcil":
        return a[:, :, None, None, None] * ops[1][:, None]
    if sub == "nka,nc,nail->nkcil":
        c, b = ops[1], ops[2]
        t = mm(a, b.reshape(n, b.shape[1], -1)).reshape(n, a.shape[1], 1, *b.shape[2:])
        return c[:, None, :, None, None] * t
    if sub == "nia,nakl->nkil":
        b = ops[1]
        i, fa = a.shape[1:]
        k, l_ = b.shape[2:]
        return mm(a, b.reshape(n, fa, k * l_)).reshape(n, i, k, l_).transpose(0, 2, 1, 3)
    return np.einsum(sub, *ops, **kw)


def _eigvalsh_2x2(H):
    if H.shape[-1] == 1:
        return H[..., 0]
    a, b, c = H[:, 0, 0], H[:, 0, 1], H[:, 1, 1]
    r = np.sqrt(0.25 * (a - c) ** 2 + b * b)
    return np.stack([0.5 * (a + c) - r, 0.5 * (a + c) + r], axis=1)


def _solve_2x2(A, b):
    if A.shape[-1] == 1:
        return b / A[:, :1, :1]
    if A.shape[-1] != 2:
        return np.linalg.solve(A, b)
    det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] * A[:, 1, 0]
    x0 = (A[:, 1, 1, None] * b[:, 0] - A[:, 0, 1, None] * b[:, 1]) / det[:, None]
    x1 = (A[:, 0, 0, None] * b[:, 1] - A[:, 1, 0, None] * b[:, 0]) / det[:, None]
    return np.stack([x0, x1], axis=1)


class _Proxy:
    """Attribute access falls through to ``target`` unless overridden."""

    def __init__(self, target, **override):
        self._target = target
        self.__dict__.update(override)

    def __getattr__(self, name):
        return getattr(self._target, name)


class fast_kernels:
    """Context manager: run the contact modules on matmul / closed-form kernels."""

    def __enter__(self):
        import dolfinx_friction.contact.friction as friction_mod
        import dolfinx_friction.contact.projection as projection_mod

        self.mods = (element_mod, projection_mod, friction_mod)
        linalg = _Proxy(np.linalg, eigvalsh=_eigvalsh_2x2, solve=_solve_2x2)
        proxy = _Proxy(np, einsum=_mm_einsum, linalg=linalg)
        for mod in self.mods:
            mod.np = proxy
        return self

    def __exit__(self, *exc):
        for mod in self.mods:
            mod.np = np


def machine():
    cpu = "unknown"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return dict(nproc=os.cpu_count(), cpu=cpu, numpy=np.__version__,
                python=platform.python_version(), blas=_blas(), memory=_memory())


def _blas():
    try:
        cfg = np.show_config(mode="dicts")  # numpy >= 1.25
        return cfg["Build Dependencies"]["blas"]["name"]
    except Exception:
        pass
    try:  # numpy < 1.25 (Debian's): linked against libblas.so.3, resolve the alternative
        libs = np.__config__.get_info("blas_opt_info").get("libraries", [])
        for d in np.__config__.get_info("blas_opt_info").get("library_dirs", []):
            path = Path(d) / "libblas.so.3"
            if "blas" in libs and path.exists():
                return f"libblas.so.3 -> {path.resolve()}"
        return ", ".join(libs) or "unknown"
    except Exception:
        return "unknown"


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
        new = old[:start] + text + ("" if end < 0 else old[end + 1:])
    RESULTS.write_text(new.rstrip("\n") + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="only up to 10^5 pairs")
    ap.add_argument("--profile", action="store_true", help="per-call-site breakdown")
    ap.add_argument("--write", action="store_true", help="record in benchmarks/RESULTS.md")
    ap.add_argument("--whatif", action="store_true",
                    help="also time the same maths on matmul / closed-form 2x2 kernels")
    args = ap.parse_args()
    sizes = SIZES[:-1] if args.quick else SIZES
    info = machine()
    info["load_start"] = os.getloadavg()[0]
    print(f"machine: {info['nproc']} cores, {info['cpu']}; numpy {info['numpy']}, "
          f"Python {info['python']}; threads pinned to 1")

    t0 = time.perf_counter()
    data = make_pairs(max(sizes))
    print(f"set-up of {max(sizes)} pairs: {time.perf_counter() - t0:.1f} s (not timed)")
    assert np.all(run(data, 0, 1000).status == SLIP)

    # chunk size scan on 10^5 pairs (or fewer), interleaved, best of 3 rounds
    n_scan = min(10**5, max(sizes))
    best_t = {c: np.inf for c in CHUNKS if c <= n_scan}
    for _ in range(3):
        for c in best_t:
            best_t[c] = min(best_t[c], time_pairs(data, n_scan, c, repeats=1))
    scan = {c: n_scan / t for c, t in best_t.items()}
    for c, r in scan.items():
        print(f"chunk {c:>7d}: {r:,.0f} pairs/s ({n_scan} pairs)")
    best_chunk = max(scan, key=scan.get)
    print(f"best chunk size: {best_chunk}")

    rows = []
    for n in sizes:
        chunk = min(best_chunk, n)
        reps = 5 if n <= 10**4 else (3 if n <= 10**5 else 2)
        t = time_pairs(data, n, chunk, reps)
        rows.append((n, chunk, t, n / t))
        print(f"{n:>8d} pairs, chunk {chunk:>6d}: {t:8.3f} s  {n / t:12,.0f} pairs/s")
    # variants, timed interleaved (best of 5 rounds) so that load from other processes
    # on the machine hits them alike
    n_w = min(10**5, max(sizes))
    variants = {("numpy", False): None, ("numpy", True): None}
    whatif = None
    if args.whatif:
        ref = run(data, 0, 1000)
        with fast_kernels():
            new = run(data, 0, 1000)
        whatif = {"dK": np.abs(new.K - ref.K).max() / np.abs(ref.K).max()}
        variants.update({("fast", False): None, ("fast", True): None})
    for _ in range(5):
        for kind, warm_start in variants:
            if kind == "fast":
                with fast_kernels():
                    t = time_pairs(data, n_w, best_chunk, 1, warm=warm_start)
            else:
                t = time_pairs(data, n_w, best_chunk, 1, warm=warm_start)
            old = variants[(kind, warm_start)]
            variants[(kind, warm_start)] = t if old is None else min(old, t)
    rates = {k: n_w / t for k, t in variants.items()}
    t = variants[("numpy", True)]
    warm = (n_w, best_chunk, t, n_w / t)
    print(f"interleaved on {n_w} pairs, chunk {best_chunk}:")
    for (kind, warm_start), r in rates.items():
        print(f"  {kind:>5s} kernels, {'warm' if warm_start else 'cold'} projection start: "
              f"{r:12,.0f} pairs/s")
    if whatif is not None:
        whatif.update(rates)
        print(f"  (fast = matmul einsums + closed-form 2x2 eigvalsh/solve; "
              f"|dK|/|K| = {whatif['dK']:.1e})")
    else:
        whatif = dict(rates)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak RSS {rss:.0f} MiB")

    prof = None
    if args.profile:
        prof = profile(data, best_chunk)
        print(f"\nprofile of one chunk of {best_chunk} pairs: {prof['total'] * 1e3:.1f} ms "
              f"(project {prof['t_proj'] * 1e3:.1f} ms in {prof['iters']} Newton sweeps "
              f"[{prof['iters_warm']} when warm-started], "
              f"face_kinematics incl. project {prof['t_kin'] * 1e3:.1f} ms, "
              f"evaluate {prof['t_eval'] * 1e3:.1f} ms)")
        for where, key, t, calls in prof["rows"][:15]:
            print(f"  {t / prof['total_prof'] * 100:5.1f}%  {t * 1e3:7.2f} ms  {calls:3d}x  "
                  f"{where:<18s} {key}")

    info["load_end"] = os.getloadavg()[0]
    if args.write:
        write_results(_section(info, scan, best_chunk, rows, warm, rss, prof, whatif))
        print(f"\nwrote {RESULTS}")


def _section(info, scan, best_chunk, rows, warm, rss, prof, whatif) -> str:
    date = datetime.date.today().isoformat()
    lines = [HEADING, "",
             f"`benchmarks/bench_element.py` ({date}): residual + consistent tangent "
             "(`face_kinematics` + `evaluate`) of node-to-surface elements on warped, deformed "
             "Q4 master faces, linear law, Coulomb friction with every pair in slip; one core "
             "(OMP/OpenBLAS threads = 1), pairs processed in chunks.", "",
             f"* machine: {info['nproc']} cores (nproc), CPU `{info['cpu']}` "
             f"(/proc/cpuinfo model name), {info['memory']} RAM",
             f"* numpy {info['numpy']} (BLAS: {info['blas']}), Python {info['python']}",
             f"* best chunk size: {best_chunk} pairs "
             "(scan on 10^5 pairs: " + ", ".join(f"{c}: {v:,.0f}/s" for c, v in scan.items())
             + ")",
             f"* peak RSS of the whole run: {rss:.0f} MiB",
             f"* 1-min load average at start / end: {info['load_start']:.1f} / "
             f"{info['load_end']:.1f} on {info['nproc']} cores (other jobs shared the machine; "
             "timings are best-of-N *CPU* times of the single-threaded process, which time-"
             "sharing does not inflate; cache and memory-bandwidth contention still can)", "",
             "| pairs | chunk | time [s] | pairs/s |", "|---:|---:|---:|---:|"]
    for n, chunk, t, rate in rows:
        lines.append(f"| {n:,} | {chunk:,} | {t:.3f} | {rate:,.0f} |")
    target = 5e5
    best = max(r[3] for r in rows)
    lines += ["", f"Target: >= {target:,.0f} pairs/s. Best measured with the package as it "
              f"is: {best:,.0f} pairs/s ({best / target:.2f} x target)."]
    cold = whatif[("numpy", False)]
    lines += ["", f"Variants on {warm[0]:,} pairs, chunk {warm[1]:,}, timed interleaved "
              "(best of 5):", "", "| kernels | projection start | pairs/s | vs. as is |",
              "|---|---|---:|---:|"]
    for (kind, warm_start), r in ((k, v) for k, v in whatif.items() if isinstance(k, tuple)):
        label = ("as is (numpy einsum, LAPACK 2x2)" if kind == "numpy" else
                 "what-if: einsums as batched matmul, closed-form 2x2 eigvalsh/solve")
        start = "previous iterate's xi (`xi0`)" if warm_start else "face centroid"
        lines.append(f"| {label} | {start} | {r:,.0f} | {r / cold:.2f}x |")
    if "dK" in whatif:
        lines += ["", "The what-if variant (`--whatif`) monkeypatches the contact modules' "
                  "`np` for the timing only (restored afterwards); it reproduces K to "
                  f"{whatif['dK']:.1e} relative."]
    lines += ["", "Memory: one evaluation peaks at about 6 kB per pair (tracemalloc), so 10^6 "
              "pairs in one call would need ~6 GB. " + _chunk_note(scan)]
    if prof is not None:
        lines += ["", f"Profile of one chunk of {best_chunk} pairs ({prof['total'] * 1e3:.1f} ms): "
                  f"`project` {prof['t_proj'] * 1e3:.1f} ms ({prof['iters']} Newton sweeps from "
                  f"the centroid, {prof['iters_warm']} from the previous iterate), "
                  f"`face_kinematics` in all {prof['t_kin'] * 1e3:.1f} ms, "
                  f"`evaluate` {prof['t_eval'] * 1e3:.1f} ms. Top numpy call sites:", "",
                  "| share | ms | calls | where | call |", "|---:|---:|---:|---|---|"]
        for where, key, t, calls in prof["rows"][:12]:
            lines.append(f"| {t / prof['total_prof'] * 100:.1f}% | {t * 1e3:.2f} | {calls} | "
                         f"{where} | `{key}` |")
    lines += ["", SUGGESTIONS.format(
        warm_gain=whatif[("numpy", True)] / cold,
        fast_gain=whatif.get(("fast", False), np.nan) / cold,
        fast_warm_gain=whatif.get(("fast", True), np.nan) / cold,
        fast_warm=whatif.get(("fast", True), np.nan))]
    return "\n".join(lines) + "\n"


def _chunk_note(scan) -> str:
    top = max(scan.values())
    good = [c for c, r in scan.items() if r >= 0.9 * top]
    big = max(scan)
    return (f"Chunks of {min(good):,}-{max(good):,} pairs are within 10 % of the best; "
            f"{big:,}-pair chunks lose {100 * (1 - scan[big] / top):.0f} % (cache).")


SUGGESTIONS = """\
Why numpy is ~10x short of 5e5 pairs/s, and what would help (element.py and projection.py
were deliberately not restructured here):

1. **The projection is over half of the time.** It makes 5 Newton sweeps from the face
   centroid, and each sweep calls `_geometry` twice (step and line-search trial), each time
   with all three contractions including the second derivatives `q_,ab`, which the trial
   does not need.  Evaluate only `q` in the trial; compute `q_,ab` once per call for faces
   whose second derivatives are constant (L2, L3, T3, T6, Q4); drop the fancy-indexed copies
   `x[active]`, `coords[active]` while every pair is still active.  Warm-start from the
   previous Newton iterate's `xi` (`face_kinematics(..., xi0=...)` exists;
   `interaction.py` does not pass it yet): {warm_gain:.2f}x measured above.
2. **`einsum` on tiny batched operands is slow** (no BLAS, generic strided loops):
   `einsum('nkab,nkd->nabd')` / `('nka,nkd->nad')` are 3-5x slower than the equivalent
   batched `matmul`, and the three-operand `einsum('nka,nc,nail->nkcil')` (master-row
   term of K) alone costs 1-2 us/pair: contract `dphi @ dxi` first, then take the outer
   product with `F_p` (4x faster).
3. **2x2 LAPACK calls**: `eigvalsh` (projection safeguard) and `solve` (Newton step and
   the dxi sensitivities) on stacks of 2x2 matrices are 3-35x slower than closed forms
   (trace/determinant, Cramer).
4. Items 2+3 together (the what-if rows) give {fast_gain:.2f}x, and with the warm start
   {fast_warm_gain:.2f}x ({fast_warm:,.0f} pairs/s).  The rest is numpy's per-call cost on stacks of
   tiny matrices (~60 such calls per evaluation) and ~6 kB of temporaries per pair.
5. **To reach >= 5e5 pairs/s, compile a fused per-pair kernel** (projection, kinematics,
   return map and K assembly in one loop over pairs: a few thousand flops per pair, ~1 us):
   numba `@njit` (a numba 0.68 wheel is on this machine's disk; compatibility with Debian's
   numpy 1.24 is unchecked), Cython, or a small C extension.  A numpy rewrite in
   structure-of-arrays layout (pair index last and contiguous, Python loops over the node /
   component indices) would also remove the tiny-matrix overhead; not measured.
"""


if __name__ == "__main__":
    main()
