"""Files without dolfinx or gmsh: checks on input files, and atomic writes.

Every file the package writes whole (``summary.json``, ``sweep.csv``, the XDMF time
series, charts and pictures, mesh-cache entries) is written through :func:`atomic_path`:
into a hidden temporary file beside it, flushed to disk (unless the caller syncs later),
then renamed into place.  A reader, or a kill at any moment, sees the old file or the new
one, never a part; a kill may leave the hidden ``.<stem>.<token>.partial<suffix>`` file,
which is never a result.
"""
from __future__ import annotations

import contextlib
import os
import secrets
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import Optional, Union

__all__ = ["atomic_path", "file_fault", "sync", "write_atomic"]


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


@contextlib.contextmanager
def atomic_path(path: Union[str, Path], durable: bool = True) -> Iterator[Path]:
    """A temporary path to write the new content of ``path`` into, for the ``with`` block.

    The temporary file is hidden, beside ``path``, with its suffix (writers that choose
    the format by the suffix see the right one) and a name of its own per call
    (concurrent writers of one path do not mix).  When the block ends it is synced to
    disk (``durable``; else it is the caller's to :func:`sync` later) and renamed onto
    ``path``; when the block raises it is removed.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.stem}.{os.getpid()}-{secrets.token_hex(4)}.partial"
                         f"{path.suffix}")
    try:
        yield tmp
        if durable:
            sync(tmp)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def sync(path: Union[str, Path]) -> None:
    """Flush a written file to disk (``fsync``)."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def write_atomic(path: Union[str, Path], data: Union[str, bytes], durable: bool = True) -> None:
    """Write ``data`` (text as UTF-8) to ``path`` through :func:`atomic_path`."""
    with atomic_path(path, durable) as tmp, open(tmp, "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)
