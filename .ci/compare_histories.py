#!/usr/bin/env python3
"""Compare the reaction columns of two ``history.csv`` files (e.g. Debian 12 vs 13).

    python3 .ci/compare_histories.py [--rtol 1e-6] [--label A] a/history.csv [--label B] b/history.csv

Both files must list the same increments (``step``, ``increment``, ``t``) and the
same reaction columns (``R_<group>_<axis>``).  A reaction component passes when

    |R_a - R_b| <= rtol * max(|R_a|, |R_b|, |R_group|)

where ``|R_group|`` is the larger Euclidean norm of that group's reaction vector
in the two files at that increment: each component is judged relative to the
magnitude of the force it belongs to, so a component that is zero up to
round-off (say R_y of a body pressed along z) is not compared relative to its
own noise.  Prints the reactions of both files side by side and the worst
relative difference per column; exits 1 when any component fails, 2 on a
malformed or mismatching input.  Plain standard library (runs anywhere).
"""
from __future__ import annotations

import argparse
import csv
import math
import re
import sys

REACTION = re.compile(r"^R_(.+)_([xyz])$")


def read(path: str) -> tuple[list[str], list[dict[str, str]]]:
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        rows = list(reader)
        return list(reader.fieldnames or []), rows


def fail(message: str) -> "NoReturn":  # noqa: F821
    print(f"compare_histories: ERROR: {message}", file=sys.stderr)
    raise SystemExit(2)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rtol", type=float, default=1e-6)
    parser.add_argument("--label", action="append", default=[],
                        help="names of the two files in the output (give it twice)")
    parser.add_argument("--quiet", action="store_true",
                        help="print only failing components and the summary")
    parser.add_argument("files", nargs=2)
    args = parser.parse_args(argv)
    labels = (args.label + ["A", "B"][len(args.label):])[:2]

    (cols_a, rows_a), (cols_b, rows_b) = read(args.files[0]), read(args.files[1])
    reactions = [c for c in cols_a if REACTION.match(c)]
    if not reactions:
        fail(f"{args.files[0]}: no reaction columns (R_<group>_<axis>)")
    if sorted(reactions) != sorted(c for c in cols_b if REACTION.match(c)):
        fail(f"the reaction columns differ: {reactions} vs "
             f"{[c for c in cols_b if REACTION.match(c)]}")
    if not rows_a:
        fail(f"{args.files[0]}: no increments")
    key = lambda r: (int(r["step"]), int(r["increment"]))  # noqa: E731
    if [key(r) for r in rows_a] != [key(r) for r in rows_b]:
        fail(f"the increments differ: {[key(r) for r in rows_a]} vs {[key(r) for r in rows_b]}")
    for ra, rb in zip(rows_a, rows_b):
        if not math.isclose(float(ra["t"]), float(rb["t"]), rel_tol=1e-12, abs_tol=1e-12):
            fail(f"step {key(ra)}: t differs ({ra['t']} vs {rb['t']})")

    groups: dict[str, list[str]] = {}
    for c in reactions:
        groups.setdefault(REACTION.match(c).group(1), []).append(c)

    worst = dict.fromkeys(reactions, 0.0)
    failures = []
    if not args.quiet:
        print(f"{'step':>4} {'inc':>3} {'column':<28} {labels[0]:>26} {labels[1]:>26} "
              f"{'rel. diff':>10}")
    for ra, rb in zip(rows_a, rows_b):
        for group, cols in groups.items():
            va = [float(ra[c]) for c in cols]
            vb = [float(rb[c]) for c in cols]
            if not all(map(math.isfinite, va + vb)):
                fail(f"step {key(ra)}: non-finite reaction of {group}")
            scale = max(math.hypot(*va), math.hypot(*vb))
            for c, a, b in zip(cols, va, vb):
                ref = max(abs(a), abs(b), scale)
                rel = abs(a - b) / ref if ref > 0.0 else 0.0
                worst[c] = max(worst[c], rel)
                flag = "" if rel <= args.rtol else "  FAIL"
                if not args.quiet or flag:
                        print(f"{key(ra)[0]:>4} {key(ra)[1]:>3} {c:<28} {a:>26.17g} {b:>26.17g} "
                          f"{rel:>10.2e}{flag}")
                if rel > args.rtol:
                    failures.append((key(ra), c, a, b, rel))
    print("worst relative difference per column: "
          + ", ".join(f"{c} {w:.2e}" for c, w in worst.items()))
    if failures:
        print(f"compare_histories: {len(failures)} reaction component(s) differ by more than "
              f"{args.rtol:g} relative between {labels[0]} and {labels[1]}", file=sys.stderr)
        return 1
    print(f"compare_histories: {len(rows_a)} increments x {len(reactions)} reaction components "
          f"agree within {args.rtol:g} relative ({labels[0]} vs {labels[1]})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
