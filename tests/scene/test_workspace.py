"""Runs that share a :class:`~dolfinx_friction.scene.workspace.Workspace` (the points of a
sweep in one warm worker) reuse the meshes, spaces and compiled forms where the scene
agrees, and give a fresh run's results and files bit for bit.  Serial and on 2 ranks (there
to round-off: PETSc sums the entries other ranks send in the order they arrive, so two
fresh runs on several ranks may differ in the last bits)."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from dolfinx_friction.reference import meshes
from dolfinx_friction.scene.runner import run
from dolfinx_friction.scene.workspace import Workspace
from tests.cli.test_cli import GOOD, edited, toml_dumps
from tests.fem.test_system import _boxes_scene

#: mu alone (everything reused), the block's E (its forms anew, the foundation's kept),
#: mu again (all reused), back to the first E (its forms, dropped meanwhile, anew)
POINTS = (["contact.0.mu=0.1"], ["contact.0.mu=0.3"], ["body.0.E=2000.0"],
          ["body.0.E=2000.0", "contact.0.mu=0.1"], ["contact.0.mu=0.2"])


def _text(path: Path, drop_wall: bool = False) -> list[str]:
    lines = path.read_text().splitlines()
    if not drop_wall:
        return lines
    wall = lines[0].split(",").index("wall_s")
    return [",".join(v for k, v in enumerate(line.split(",")) if k != wall) for line in lines]


def test_runs_sharing_a_workspace_equal_fresh_runs(shared_dir, comm):
    scene = shared_dir / "scene.toml"
    meshes.two_boxes(shared_dir / "two.msh", n_block=(2, 2, 1), n_foundation=(3, 3, 1))
    if comm.rank == 0:
        scene.write_text(toml_dumps(edited(GOOD, [("output.fields", True)])))
    comm.barrier()
    workspace, last = Workspace(), None
    for k, sets in enumerate(POINTS):
        ours = run(scene, shared_dir / f"ours{k}", sets, comm=comm, workspace=workspace)
        fresh = run(scene, shared_dir / f"fresh{k}", sets, comm=comm)
        scale = max(np.abs(r).max() for inc in fresh.increments for r in inc.reactions.values())
        for a, b in zip(ours.increments, fresh.increments, strict=True):
            assert a.iterations == b.iterations
            for group in a.reactions:
                if comm.size == 1:
                    assert np.array_equal(a.reactions[group], b.reactions[group]), (sets, group)
                else:
                    assert np.allclose(a.reactions[group], b.reactions[group], rtol=0,
                                       atol=1e-12 * scale), (sets, group)
        if last is not None:  # the same mesh and spaces, the foundation's compiled forms
            assert ours.problem.meshes is last.problem.meshes
            assert ours.problem.fields[1].u is last.problem.fields[1].u
            assert ours.problem.system.bodies[1] is last.problem.system.bodies[1]
            same_block = ours.problem.scene.bodies[0] == last.problem.scene.bodies[0]
            assert (ours.problem.system.bodies[0] is last.problem.system.bodies[0]) \
                == same_block
        last = ours
        if comm.size == 1:
            a, b = ours.directory, fresh.directory
            assert _text(a / "history.csv", True) == _text(b / "history.csv", True)
            for name in ("contact.csv", "fields/block.xdmf", "fields/foundation.xdmf",
                         "fields/step1_increment0003/block.xdmf"):
                assert (a / name).read_bytes() == (b / name).read_bytes(), (sets, name)


def _resident_mib() -> float:
    """This process's resident memory now [MiB] (Linux)."""
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def test_runs_sharing_a_workspace_keep_nothing_of_each_other(shared_dir, comm):
    """A run frees its factorisations when it ends, and then the PETSc objects of the run
    before it (dropped since: petsc4py destroys a collected object only in
    ``PETSc.garbage_cleanup`` on its mesh's communicator), so a warm worker does not grow
    from point to point: six runs of a scene on the condensed path (a factorisation kept
    for the run, MUMPS) sharing a workspace grow each rank by less than 12 MiB from the
    second run to the sixth (measured 2.5 MiB serially, 3.5 on 2 ranks, most of it the
    allocator's: 0.4 MiB after ``malloc_trim``; 75 MiB before the fix).  The solver answers
    for its settings after the run."""
    mesh = meshes.two_boxes(shared_dir / "deep_boxes.msh", n_foundation=(5, 5, 10))
    scene = _boxes_scene(mesh, mu=0.3)
    workspace, resident = Workspace(), []
    for _ in range(6):
        result = run(scene, write=False, comm=comm, workspace=workspace)
        assert result.solver.linear.condensed_solves > 0
        assert result.solver.linear.settings()["factor_solver_type"] == "mumps"
        del result
        resident.append(_resident_mib())
    assert resident[-1] - resident[1] < 12.0, resident
