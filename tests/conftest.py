"""Shared fixtures: the suite runs serially and under ``mpirun -n 2``, numpy started as the
command line starts it (without huge-page advice: :mod:`dolfinx_friction.cli.environment`)."""
from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from dolfinx_friction.cli import environment

environment.prepare()  # before numpy is imported

import pytest  # noqa: E402
from mpi4py import MPI  # noqa: E402


@pytest.fixture
def comm() -> MPI.Comm:
    return MPI.COMM_WORLD


@pytest.fixture
def shared_dir():
    """A temporary directory made on rank 0 and known to every rank."""
    comm = MPI.COMM_WORLD
    path = comm.bcast(tempfile.mkdtemp(prefix="dfx_") if comm.rank == 0 else None, root=0)
    yield Path(path)
    comm.barrier()
    if comm.rank == 0:
        shutil.rmtree(path, ignore_errors=True)


def pytest_runtest_logreport(report):
    """Under MPI a failure on one rank would leave the others waiting in a collective:
    print it and abort all ranks instead."""
    comm = MPI.COMM_WORLD
    if comm.size > 1 and report.failed:
        import sys
        print(f"\n[rank {comm.rank}] FAILED {report.nodeid}\n{report.longreprtext}",
              file=sys.stderr, flush=True)
        comm.Abort(1)
