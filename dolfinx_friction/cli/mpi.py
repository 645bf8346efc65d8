"""MPI in a command-line process: what the launcher says, read before MPI starts (nothing
here imports mpi4py), and :func:`start`, which starts it."""
from __future__ import annotations

import os
import sys
from types import ModuleType
from typing import Mapping

__all__ = ["LAUNCHER_RANKS", "LAUNCHER_SIZES", "rank", "ranks", "SINGLETON",
           "singleton_settings", "start"]

#: What MPI launchers (Open MPI, PMIx, MPICH's PMI, MVAPICH) set in each rank's
#: environment to its rank, and to the number of ranks (MPICH: ranks on the node).
LAUNCHER_RANKS = ("OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK", "MV2_COMM_WORLD_RANK")
LAUNCHER_SIZES = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "MPI_LOCALNRANKS", "MV2_COMM_WORLD_SIZE")


def _first(names: tuple[str, ...]) -> int | None:
    for name in names:
        if os.environ.get(name, "").isdigit():
            return int(os.environ[name])
    return None


def rank() -> int:
    """This process's MPI rank, without initialising MPI just to print an error."""
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is not None and mpi.Is_initialized() and not mpi.Is_finalized():
        return mpi.COMM_WORLD.rank
    found = _first(LAUNCHER_RANKS)
    return 0 if found is None else found


def ranks() -> int:
    """The number of ranks the launcher started (1 without a launcher)."""
    found = _first(LAUNCHER_SIZES)
    return 1 if found is None else found


#: Open MPI settings of a process started without a launcher (an MPI singleton), which has
#: no peer to talk to: no daemon (Open MPI 4 starts ``orted`` for a singleton, which only
#: spawning processes need: ~0.3 s of wall time, ``benchmarks/bench_small.py``), and only
#: the transports it uses, ``ob1`` over ``self`` (what Open MPI selects there anyway), so
#: that no other layer probes for network hardware first: MPI_Init's wall time 0.23 ->
#: 0.03 s on Debian 12 (Open MPI 4.1: the ``cm`` layer's PSM probes), 1.6 -> 0.55 s in sid
#: (Open MPI 6.0: the ``ofi`` transport's libfabric), CPU 0.03-0.5 s either way.  Open MPI 5
#: and 6 ignore the first, as they ignore every unknown ``OMPI_MCA_``.
SINGLETON = {"OMPI_MCA_ess_singleton_isolated": "1", "OMPI_MCA_pml": "ob1",
             "OMPI_MCA_btl": "self"}


def singleton_settings(environ: Mapping[str, str] = os.environ) -> dict[str, str]:
    """The :data:`SINGLETON` settings a process with the environment ``environ`` adds: none
    under a launcher (one of its rank variables set), none the user set."""
    if any(name in environ for name in LAUNCHER_RANKS):
        return {}
    return {name: value for name, value in SINGLETON.items() if name not in environ}


def start() -> ModuleType:
    """``mpi4py.MPI``, imported (MPI initialised) with :func:`singleton_settings`, which leave
    the environment once MPI has read them: a process started from this one (an ``mpirun``
    among them) inherits the environment this one was given (``btl = self`` would leave
    its ranks no transport to each other).  Where mpi4py.MPI was imported already, MPI
    started then, without these settings."""
    if "mpi4py.MPI" in sys.modules:
        return sys.modules["mpi4py.MPI"]
    added = singleton_settings()
    os.environ.update(added)
    try:
        from mpi4py import MPI
    finally:
        for name in added:
            os.environ.pop(name, None)
    return MPI
