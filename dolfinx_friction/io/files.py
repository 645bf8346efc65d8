"""Checks on input files that need neither dolfinx nor gmsh."""
from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import Optional, Union

__all__ = ["file_fault"]


def file_fault(path: Union[str, Path]) -> Optional[str]:
    """Why ``path`` cannot be read as an input file ("no such file", "is a FIFO, not a
    regular file", ...), or None for a regular file.  Never opens the file."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return "no such file"
    except OSError as e:
        return f"cannot be read ({e.strerror})"
    if stat.S_ISDIR(mode):
        return "is a directory, not a file"
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISFIFO(mode):
        kind = "a FIFO"
    elif stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        kind = "a device"
    elif stat.S_ISSOCK(mode):
        kind = "a socket"
    else:  # pragma: no cover
        kind = "special"
    return f"is {kind}, not a regular file"
