"""What successive runs in one process share: meshes, spaces, compiled forms and
expressions, kept from one run to the next (the points of a sweep in a warm worker).

A run given a :class:`Workspace` (``run(..., workspace=ws)``) asks it for each such object
by a key that holds everything the object depends on (the mesh file and its state, the
bodies' discretisation, their materials); the objects made for the previous run are
reused where the keys agree, and the displacements they hold are zeroed, so a run gives
the results of a fresh process bit for bit.  What the previous run made and this one
does not ask for is dropped when the next run starts: at most two runs' objects are
kept.  No dolfinx here.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Callable, Hashable, TypeVar, Union

__all__ = ["Workspace", "file_key"]

T = TypeVar("T")


def file_key(path: Union[str, Path]) -> tuple:
    """A file's identity and state: its resolved path, inode, size and modification time
    (a file rewritten in place is another key)."""
    path = Path(path).resolve()
    st = os.stat(path)
    return str(path), st.st_ino, st.st_size, st.st_mtime_ns


class Workspace:
    """Objects kept from one run to the next, by key."""

    def __init__(self) -> None:
        self._used: dict[Hashable, object] = {}
        self._kept: dict[Hashable, object] = {}

    def start(self) -> None:
        """A run begins: what the last run used stays available, the rest is dropped."""
        self._kept, self._used = self._used, {}

    def values(self) -> list:
        """Every object it holds (those the last run used, then the older ones), in the
        order they were made or reused."""
        return [*self._used.values(), *self._kept.values()]

    def get(self, key: Hashable, make: Callable[[], T]) -> T:
        """The object of ``key``: the one kept for it, else ``make()``."""
        if key not in self._used:
            self._used[key] = self._kept.pop(key) if key in self._kept else make()
        return self._used[key]  # type: ignore[return-value]
