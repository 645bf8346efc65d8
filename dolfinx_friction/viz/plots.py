"""Charts of written results with matplotlib (``dolfinx-friction plot``), without a display
and without dolfinx.

* :func:`plot_history`: a run's ``history.csv`` against the pseudo-time ``t``: the
  reactions (and the forces on rigid obstacles), the Newton iterations of every converged
  increment, and the slave nodes in contact and slipping;
* :func:`plot_sweep`: a sweep's ``sweep.csv``: the final reactions of the converged points
  against each swept value, one line per combination of the other swept values.

Components that stay zero (below 1e-9 of the largest force of the chart) are left out.
Files are written whole or not at all; the format follows the file's suffix (png, pdf,
svg, ...).
"""
from __future__ import annotations

import io
import itertools
from pathlib import Path
from typing import Sequence, Union

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from dolfinx_friction.io.files import write_atomic
from dolfinx_friction.io.reader import ResultsError, RunFiles, read_csv

__all__ = ["plot_history", "plot_sweep"]

_ZERO = 1e-9


def _label(column: str) -> str:
    """``R_block_top_x`` -> ``R block_top x``."""
    kind, rest = column.split("_", 1)
    group, _, axis = rest.rpartition("_")
    return f"{kind} {group} {axis}"


def _nonzero(columns: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The columns that are not zero throughout (relative to the largest value of all)."""
    top = max((float(np.nanmax(np.abs(v))) for v in columns.values() if v.size), default=0.0)
    return {c: v for c, v in columns.items() if v.size and np.nanmax(np.abs(v)) > _ZERO * top}


def _save(fig: Figure, path: Path) -> Path:
    fmt = path.suffix.lstrip(".").lower() or "png"
    if fmt not in fig.canvas.get_supported_filetypes():
        raise ResultsError(f"{path}: unknown picture format {fmt!r} (png, pdf, svg, ...)")
    buffer = io.BytesIO()
    fig.savefig(buffer, format=fmt, dpi=120)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(path, buffer.getvalue())
    return path


def _state(run: RunFiles) -> str:
    """How the run ended, for the chart's title."""
    if run.summary is None:
        return f"incomplete run (no summary.json): {len(run.history)} converged increments"
    if not run.summary.get("converged", True):
        return f"did not converge: {run.summary.get('failure') or ''}".rstrip(": ")
    return f"{len(run.history)} converged increments"


def plot_history(run: RunFiles, path: Path) -> Path:
    """Three charts of a run's history against ``t`` into ``path``."""
    t = np.array(run.column("t"))
    fig = Figure(figsize=(9.5, 9.0), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    fig.suptitle(f"{run.title()}\n{_state(run)}", fontsize=10)
    forces = _nonzero({c: np.array(run.column(c)) for c in run.force_columns()
                       if not c.startswith("U_")})
    for column, values in forces.items():
        axes[0].plot(t, values, "o-" if len(t) < 40 else "-", ms=3, label=_label(column))
    axes[0].set_ylabel("force")
    axes[0].set_title("reactions (R) and forces on rigid obstacles (F)", fontsize=9)
    if forces:
        axes[0].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[1].bar(t, run.column("newton_iterations"),
                width=0.6 * float(np.min(np.diff(t))) if len(t) > 1 else 0.1, color="#4c72b0")
    axes[1].set_ylabel("Newton iterations")
    axes[1].yaxis.set_major_locator(MaxNLocator(integer=True))
    axes[2].yaxis.set_major_locator(MaxNLocator(integer=True))
    axes[1].set_title("Newton iterations per converged increment", fontsize=9)
    axes[2].plot(t, run.column("active"), "o-", ms=3, label="in contact")
    axes[2].plot(t, run.column("slipping"), "s-", ms=3, label="slipping")
    axes[2].set_ylabel("slave nodes")
    axes[2].set_xlabel("pseudo-time t (step index + step time)")
    axes[2].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    steps = (run.summary or {}).get("steps") or []
    for ax in axes:
        ax.grid(alpha=0.3)
        for k in range(1, int(np.ceil(t.max())) if len(t) else 0):  # step boundaries
            ax.axvline(k, color="0.6", lw=0.8, ls=":")
    for k, name in enumerate(steps):  # a step's name where its increments start
        if len(t) and k < t.max() and (k >= t.min() or k + 1 > t.min() > k):
            axes[0].annotate(name, (max(k, t.min()), 1.0), xycoords=("data", "axes fraction"),
                             xytext=(3, -3), textcoords="offset points", va="top",
                             fontsize=8, color="0.4")
    if not len(t):
        axes[0].text(0.5, 0.5, "no converged increment", transform=axes[0].transAxes,
                     ha="center")
    return _save(fig, path)


def _flat_as_flat(ax, values: np.ndarray) -> None:
    """A value that does not change (to 1e-6 relative) is drawn as a flat line, not as its
    round-off magnified to the height of the chart."""
    values = values[np.isfinite(values)]
    if values.size and np.ptp(values) <= 1e-6 * np.abs(values).max():
        middle, half = float(values.mean()), 0.05 * float(np.abs(values).max()) or 1.0
        ax.set_ylim(middle - half, middle + half)
        ax.ticklabel_format(axis="y", useOffset=False)


def _float(text: str) -> float:
    """A number of sweep.csv; NaN for an empty cell (a column another point has)."""
    return float(text) if text else np.nan


def _numbers(values: Sequence[str]) -> Union[np.ndarray, None]:
    try:
        return np.array([float(v) for v in values])
    except ValueError:
        return None


def plot_sweep(directory: Path, path: Path) -> tuple[Path, int]:
    """Final reactions against each swept value of ``directory/sweep.csv`` into ``path``;
    returns the path and the number of failed points (listed, not drawn)."""
    header, rows = read_csv(directory / "sweep.csv")
    if "folder" not in header or "converged" not in header:
        raise ResultsError(f"{directory / 'sweep.csv'}: not a sweep table (no folder and "
                           "converged columns)")
    keys = header[header.index("folder") + 1: header.index("converged")]
    good = [r for r in rows if r["converged"] == "true"]
    forces = [c for c in header if c.startswith(("R_", "F_"))]
    swept = [k for k in keys if len({r[k] for r in rows}) > 1] or keys[:1]
    values = {c: np.array([_float(r[c]) for r in good]) for c in forces}
    shown = list(_nonzero(values)) if good else []
    n_rows, n_cols = max(len(shown), 1), max(len(swept), 1)
    fig = Figure(figsize=(4.5 * n_cols + 1.5, 2.6 * n_rows + 1.0), layout="constrained")
    axes = np.atleast_2d(fig.subplots(n_rows, n_cols, squeeze=False))
    failed = len(rows) - len(good)
    fig.suptitle(f"sweep {directory.name}: final values of {len(good)} converged point"
                 + ("s" if len(good) != 1 else "")
                 + (f" ({failed} failed, not drawn)" if failed else ""), fontsize=10)
    for col, key in enumerate(swept):
        others = [k for k in swept if k != key]
        order = list(dict.fromkeys(r[key] for r in rows))  # as listed on the command line
        numeric = _numbers(order)
        for combo in itertools.product(*(list(dict.fromkeys(r[k] for r in rows))
                                         for k in others)):
            members = [r for r in good if all(r[k] == v for k, v in zip(others, combo))]
            members.sort(key=lambda r: order.index(r[key]))
            x = [order.index(r[key]) if numeric is None else float(r[key]) for r in members]
            label = ", ".join(f"{k} = {v}" for k, v in zip(others, combo)) or None
            for row_k, column in enumerate(shown):
                axes[row_k, col].plot(x, [_float(r[column]) for r in members], "o-", ms=4,
                                      label=label)
        for row_k in range(n_rows):
            ax = axes[row_k, col]
            ax.grid(alpha=0.3)
            if row_k < len(shown):
                _flat_as_flat(ax, values[shown[row_k]])
            if numeric is None:
                ax.set_xticks(range(len(order)), order, rotation=20, fontsize=8)
            if row_k < len(shown):
                ax.set_ylabel(f"final {_label(shown[row_k])}", fontsize=9)
            if row_k == 0 and others and shown:
                ax.legend(fontsize=7, loc="best")
        axes[-1, col].set_xlabel(key)
    if not shown:
        axes[0, 0].text(0.5, 0.5, "no converged point with a non-zero reaction",
                        transform=axes[0, 0].transAxes, ha="center")
    return _save(fig, path), failed
