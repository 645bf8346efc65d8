"""On-disk cache of what is read from a mesh file, so that a repeated run skips gmsh.

Loading gmsh (its shared library) takes about 0.5 s of CPU time, more than the rest of
reading a small mesh and, on a scene of 1k dofs, a tenth of the whole run
(``benchmarks/bench_small.py``).  A mesh file that was read once is read again from
this cache: a ``.npz`` file (no pickle) of named arrays and a JSON header.

* Key: the SHA-256 of the file's bytes (as read through the open descriptor that
  would be given to gmsh), the body names, the reader's own identity (the caller passes
  the hash of its source: a changed reader never sees entries of the old one), the
  package version and :data:`FORMAT`; a changed file, other bodies or another reader is
  a miss.
* Where: ``$DOLFINX_FRICTION_CACHE``, else ``$XDG_CACHE_HOME/dolfinx_friction``, else
  ``~/.cache/dolfinx_friction``; the entries are in its ``meshes`` folder.
  ``DOLFINX_FRICTION_CACHE=off`` switches the cache off.
* Only files up to :data:`MAX_FILE_BYTES` are cached (beyond, gmsh's start-up is a
  small share of the run); at most :data:`MAX_ENTRIES` entries are kept, the least
  recently written go first.
* An entry that cannot be read or written is skipped (logged at DEBUG): the mesh is
  then read with gmsh, as without the cache.  Entries are written atomically, so
  concurrent runs never see half an entry.
"""
from __future__ import annotations

import hashlib
import json
import logging
import os
from pathlib import Path
from typing import Optional, Sequence

import numpy as np

from dolfinx_friction import __version__
from dolfinx_friction.io.files import atomic_path

ENV = "DOLFINX_FRICTION_CACHE"
FORMAT = 1
MAX_FILE_BYTES = 16 << 20
MAX_ENTRIES = 256
_log = logging.getLogger(__name__)


def directory() -> Optional[Path]:
    """The folder of the mesh entries, or None when the cache is off."""
    root = os.environ.get(ENV, "")
    if root.strip().lower() == "off":
        return None
    if not root:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(Path.home(), ".cache")
        root = os.path.join(base, "dolfinx_friction")
    return Path(root) / "meshes"


def key(fd: int, body_names: Sequence[str], reader: str) -> Optional[str]:
    """The entry name of the open mesh file ``fd`` read for ``body_names`` by ``reader``
    (a string that changes when the reader does); None when the cache is off or the file
    is too large to be cached."""
    if directory() is None or os.fstat(fd).st_size > MAX_FILE_BYTES:
        return None
    digest = hashlib.sha256()
    offset = 0
    while block := os.pread(fd, 1 << 20, offset):
        digest.update(block)
        offset += len(block)
    digest.update(json.dumps([FORMAT, __version__, reader, list(body_names)]).encode())
    return digest.hexdigest()


def load(name: str) -> Optional[tuple[dict, dict[str, np.ndarray]]]:
    """``(header, arrays)`` of the entry ``name``, or None if there is none readable."""
    path = directory() / f"{name}.npz"
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
        header = json.loads(str(arrays.pop("__header__")))
    except FileNotFoundError:
        return None
    except Exception as exc:  # a damaged entry: read the mesh again
        _log.debug("mesh cache entry %s unreadable: %s", path, exc)
        return None
    return header, arrays


def store(name: str, header: dict, arrays: dict[str, np.ndarray]) -> None:
    """Write the entry ``name`` (atomically); drop the oldest beyond :data:`MAX_ENTRIES`."""
    folder = directory()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with atomic_path(folder / f"{name}.npz") as tmp, open(tmp, "wb") as f:
            np.savez(f, __header__=np.array(json.dumps(header)), **arrays)
        entries = sorted((p for p in folder.glob("*.npz") if not p.name.startswith(".")),
                         key=lambda p: p.stat().st_mtime)  # (not the others' partial files)
        for old in entries[:max(len(entries) - MAX_ENTRIES, 0)]:
            old.unlink(missing_ok=True)
    except (OSError, TypeError, ValueError) as exc:
        _log.debug("mesh cache entry %s not written: %s", name, exc)
