"""What the MPI launcher says, read before MPI starts (nothing here imports mpi4py)."""
from __future__ import annotations

import os
import sys

__all__ = ["LAUNCHER_RANKS", "LAUNCHER_SIZES", "rank", "ranks", "no_singleton_daemon"]

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


def no_singleton_daemon() -> None:
    """A run started without a launcher is an MPI singleton, for which Open MPI 4 starts a
    daemon (orted) that only spawning processes needs (the package never spawns): ~0.3 s of
    wall time at start-up (``benchmarks/bench_small.py``).  Ask for none, before mpi4py is
    imported; under a launcher (its rank variables set) nothing changes.  Open MPI 5 does
    not know the variable and ignores it, as it ignores every unknown ``OMPI_MCA_``."""
    if not any(name in os.environ for name in LAUNCHER_RANKS):
        os.environ.setdefault("OMPI_MCA_ess_singleton_isolated", "1")
