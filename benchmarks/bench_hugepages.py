"""numpy's transparent huge-page advice on and off: the same runs, in fresh processes.

    python benchmarks/bench_hugepages.py            # 3 rounds of every case, both settings
    python benchmarks/bench_hugepages.py --rounds 1 --no-results

numpy advises the kernel to back every array of 4 MiB or more with huge pages
(``madvise(MADV_HUGEPAGE)``); with the kernel's ``defrag = madvise`` a page fault in such an
array compacts memory synchronously when no free huge page is left.  The command line
starts numpy without that advice (:mod:`dolfinx_friction.cli.environment`); this measures
what that does on scenes whose arrays are that large.  Each run is a new process (numpy
reads ``NUMPY_MADVISE_HUGEPAGE`` at import) that solves one case after an untimed
one-increment warm-up; the settings alternate within each round.  Per run: CPU seconds of
the timed ``run()``, its system-time share and minor page faults (``getrusage``).

Cases: the full-size finite-strain ironing of ``bench_ccx_nlgeom.py`` (21,996 dofs), the
one-layer Hertz at h = 0.05 (22,716 dofs) and the 3D block at n = 8 (35,451 dofs,
frictionless and mu = 0.3) of ``bench_ccx.py --kinds``.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import _bench as B  # noqa: I001

#: ``bench_ccx_nlgeom.py``'s case name, or the label of a case of ``bench_ccx.py --kinds``
CASES = ("ironing (full)", "hertz_h0.05", "block3d_n8_mu0", "block3d_n8_mu0.3")
THP = Path("/sys/kernel/mm/transparent_hugepage")
#: what the table does not show (measured 2026-12-05 on the Intel Xeon of the first run)
NOTES = """What happens (measured inside the full ironing's run, advice on): at each new matrix
pattern, a fresh 10 MB index array took 80-170 ms to fill instead of 2 ms, with 450-650
minor faults of ~0.28 ms of system time each: the kernel compacting memory to find a huge
page for a fault in an advised region (`defrag = madvise`, Debian's default, on a machine
whose 24 GiB were 2.7 GiB page cache and fragmented after hours of use).  Without the
advice the same array faults its 2,500 small pages in 3 ms.  In a fresh interpreter the
same allocation takes 2 ms either way, so the cost depends on the machine's memory state:
a quiet machine just booted shows no difference; one that has run for a while loses a
quarter to a third of the 3D runs.  Small scenes (arrays below numpy's 4 MiB threshold) are
unaffected (the hertz_sphere, sliding_block and ironing_neo_hookean demos within +-3 %,
alternating runs).  The answers do not change (the table's last column).  So the command
line starts numpy without the advice (`dolfinx_friction.cli.environment`, the user's own
`NUMPY_MADVISE_HUGEPAGE` kept), the benchmarks and the test suite do the same, and the
README tells script users to set it.  Every CPU figure in this file measured before
2026-12-05 06:00 (5a4cfd7) ran with the advice on."""


def scene(case: str):
    """The case's :class:`~dolfinx_friction.scene.model.Scene`."""
    if case == "ironing (full)":
        from bench_ccx_nlgeom import cases
        return dict((name, make) for name, make, _ in cases(False))[case]()
    import bench_ccx
    kind = case.split("_")[0]
    return next(c for c in bench_ccx.kind_cases(kind, False) if c.label == case).make()


def one(case: str) -> dict:
    """Solve ``case`` in this process: CPU seconds, system seconds, minor faults."""
    s = scene(case)
    B.timed_run(s, max_increments=1)
    r0 = resource.getrusage(resource.RUSAGE_SELF)
    result, num = B.timed_run(s)
    r1 = resource.getrusage(resource.RUSAGE_SELF)
    return {"cpu": num["cpu"], "system": r1.ru_stime - r0.ru_stime,
            "faults": r1.ru_minflt - r0.ru_minflt, "dofs": num["dofs"],
            "newton": num["newton"],
            "reactions": [[float(c) for v in i.reactions.values() for c in v]
                          for i in result.increments]}


def best(runs: list[dict], key: str) -> float:
    """The lowest ``key`` of ``runs``."""
    return min(r[key] for r in runs)


def spawn(case: str, advice: str) -> dict:
    """``one(case)`` in a new process with ``NUMPY_MADVISE_HUGEPAGE=advice``."""
    env = {**os.environ, "NUMPY_MADVISE_HUGEPAGE": advice}
    out = subprocess.run([sys.executable, __file__, "--one", case], env=env, check=True,
                         capture_output=True, text=True, timeout=3600)
    return json.loads(out.stdout.strip().splitlines()[-1])


def kernel() -> str:
    """The kernel's transparent huge-page settings."""
    def read(name: str) -> str:
        return (THP / name).read_text().strip() if (THP / name).exists() else "?"
    return f"transparent_hugepage enabled `{read('enabled')}`, defrag `{read('defrag')}`"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--no-results", action="store_true")
    ap.add_argument("--one", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps(one(args.one)))
        return 0
    machine = B.machine()
    cases = args.cases.split(",")
    runs: dict[tuple[str, str], list[dict]] = {}
    for k in range(args.rounds):
        for case in cases:
            for advice in (("1", "0") if k % 2 == 0 else ("0", "1")):
                t0 = time.perf_counter()
                r = spawn(case, advice)
                runs.setdefault((case, advice), []).append(r)
                print(f"round {k + 1} {case} advice {advice}: {r['cpu']:.2f} s CPU, "
                      f"{r['system']:.2f} s system, {r['faults']} faults "
                      f"({time.perf_counter() - t0:.0f} s)", flush=True)
    rows = []
    for case in cases:
        on, off = runs[(case, "1")], runs[(case, "0")]
        rows.append([case, f"{on[0]['dofs']:,}", f"{on[0]['newton']}",
                     " / ".join(f"{r['cpu']:.2f}" for r in on),
                     " / ".join(f"{r['cpu']:.2f}" for r in off),
                     f"{best(off, 'cpu') / best(on, 'cpu'):.2f}",
                     f"{best(on, 'system'):.2f} / {best(off, 'system'):.2f}",
                     f"{best(on, 'faults'):,} / {best(off, 'faults'):,}",
                     "yes" if all(r["reactions"] == on[0]["reactions"] for r in on + off)
                     else "no"])
    text = "\n".join([
        "`benchmarks/bench_hugepages.py`: numpy's huge-page advice on (numpy's default) and "
        "off (what the command line, the benchmarks and the tests start numpy with), the "
        "same run in fresh processes, alternating; CPU seconds of the run after a "
        "one-increment warm-up.", "",
        f"* {B.machine_line(machine, B.load_average())}; kernel {kernel()}", "",
        B.table(["case", "dofs", "Newton its", "CPU [s] advice on (each round)",
                 "CPU [s] advice off", "off / on (best of each)",
                 "system [s] on / off (best)", "minor faults on / off (fewest)",
                 "reactions bit for bit"], rows, "lrrrrrrrl"), "", NOTES])
    print(text)
    if not args.no_results:
        B.write_section("Huge pages: numpy's advice on and off", text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
