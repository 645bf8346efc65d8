"""Settings a command-line process gives the libraries it starts, before they read them
(nothing here imports them).

numpy asks the kernel for transparent huge pages on every array of 4 MiB or more
(``madvise``); where the kernel's ``defrag`` setting is ``madvise`` (Debian's default), a
page fault in such an array compacts memory on the spot when no free huge page is left.
On a machine whose memory is fragmented (any that has run for a while) that made each
fault cost ~0.3 ms of system time: a fresh 10 MB array took 80-170 ms to fill instead of 2,
a third of the 35k-dof 3D block's run (benchmarks/RESULTS.md, "Huge pages: numpy's advice
on and off").  A command-line process therefore starts numpy without that advice
(:data:`NUMPY`), unless the user set it; a script sets ``NUMPY_MADVISE_HUGEPAGE=0`` itself.
"""
from __future__ import annotations

import os
import sys
from typing import MutableMapping

__all__ = ["NUMPY", "prepare"]

#: numpy without its huge-page advice (read once, when numpy is imported)
NUMPY = {"NUMPY_MADVISE_HUGEPAGE": "0"}


def prepare(environ: MutableMapping[str, str] = os.environ) -> bool:
    """Put :data:`NUMPY` into ``environ`` where the user has not set its variables (a
    process started from this one, as the sweep's workers are, inherits them); whether
    numpy runs with what ``environ`` says: it is not imported yet, or the variables were
    set already (by whoever started this process)."""
    given = all(name in environ for name in NUMPY)
    for name, value in NUMPY.items():
        environ.setdefault(name, value)
    return given or "numpy" not in sys.modules
