"""What the MPI launcher says, read before MPI starts (nothing here imports mpi4py)."""
from __future__ import annotations

import os
import sys

__all__ = ["LAUNCHER_RANKS", "LAUNCHER_SIZES", "rank", "ranks", "SINGLETON", "singleton_settings"]

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


def singleton_settings() -> None:
    """Apply :data:`SINGLETON` (where the user set none of them) before mpi4py is imported,
    in a process that no launcher started (none of its rank variables set); under a
    launcher nothing changes."""
    if not any(name in os.environ for name in LAUNCHER_RANKS):
        for name, value in SINGLETON.items():
            os.environ.setdefault(name, value)
