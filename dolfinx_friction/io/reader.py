"""Reading a results folder that a run wrote (``history.csv``, ``summary.json``), for the
commands that draw or collect results after the run (``plot``, ``render``, ``sweep``).

Nothing here imports dolfinx.  A folder is a *results folder* when it holds
``history.csv``; it is *complete* when it also holds ``summary.json`` (written when the
solve ends: converged or not).  A run killed half-way leaves ``history.csv`` (its
converged increments) without ``summary.json``.
"""
from __future__ import annotations

import csv
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Union

__all__ = ["ResultsError", "RunFiles", "read_csv", "read_run"]


class ResultsError(ValueError):
    """A folder or file that cannot be read as results (one line, naming it)."""


def read_csv(path: Path) -> tuple[list[str], list[dict[str, str]]]:
    """Header and rows of a CSV table; a last line without its newline (cut by a kill) is
    left out."""
    try:
        text = path.read_text()
    except OSError as exc:
        raise ResultsError(f"{path}: cannot be read: {exc.strerror or exc}") from None
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]
    lines = list(csv.reader(text.splitlines()))
    if not lines:
        raise ResultsError(f"{path}: empty (no header row)")
    header = lines[0]
    rows = [dict(zip(header, line)) for line in lines[1:] if len(line) == len(header)]
    return header, rows


@dataclass
class RunFiles:
    """What a results folder holds: the rows of ``history.csv`` (one per converged
    increment, values as written) and ``summary.json`` (None for a run killed half-way)."""

    directory: Path
    header: list[str]
    history: list[dict[str, str]]
    summary: Optional[dict]

    @property
    def complete(self) -> bool:
        return self.summary is not None

    def column(self, name: str) -> list[float]:
        """One column of ``history.csv`` as numbers (one per converged increment)."""
        return [float(row[name]) for row in self.history]

    def force_columns(self) -> list[str]:
        """The reaction (``R_*``) and rigid-obstacle (``U_*``, ``F_*``) columns."""
        return [c for c in self.header if c.startswith(("R_", "U_", "F_"))]

    def title(self) -> str:
        """The scene's title (from ``summary.json``), else the folder's name."""
        title = (self.summary or {}).get("title")
        return title or self.directory.name


def read_run(directory: Union[str, Path]) -> RunFiles:
    """Read a results folder; :class:`ResultsError` when it is none."""
    directory = Path(directory)
    if not directory.is_dir():
        raise ResultsError(f"{directory}: no such folder" if not directory.exists()
                           else f"{directory}: not a folder")
    history = directory / "history.csv"
    if not history.is_file():
        raise ResultsError(f"{directory}: not a results folder (no history.csv)")
    header, rows = read_csv(history)
    summary = None
    path = directory / "summary.json"
    if path.is_file():
        try:
            summary = json.loads(path.read_text())
        except (OSError, ValueError) as exc:
            raise ResultsError(f"{path}: cannot be read: {exc}") from None
    return RunFiles(directory, header, rows, summary)
