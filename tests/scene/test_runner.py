"""``run(..., max_increments=)``: a run stopped after its first increments writes and
returns exactly those, equal to the same increments of the whole run.  Serial and on 2
ranks."""
from __future__ import annotations

import json

import numpy as np

from dolfinx_friction.reference import meshes
from dolfinx_friction.scene.runner import run
from tests.cli.test_cli import GOOD, read_csv, toml_dumps


def test_a_run_stops_after_max_increments(shared_dir, comm):
    scene = shared_dir / "scene.toml"
    meshes.two_boxes(shared_dir / "two.msh", n_block=(2, 2, 1), n_foundation=(3, 3, 1))
    if comm.rank == 0:
        scene.write_text(toml_dumps(GOOD))
    comm.barrier()
    whole = run(scene, shared_dir / "whole", comm=comm)
    first = run(scene, shared_dir / "first", comm=comm, max_increments=2)
    assert whole.summary.converged and len(whole.increments) > 2
    assert not first.summary.converged and not first.summary.failure
    assert first.summary.increments == len(first.increments) == 2
    for a, b in zip(first.increments, whole.increments[:2]):
        assert (a.step, a.increment, a.iterations) == (b.step, b.increment, b.iterations)
        for group in a.reactions:
            assert np.allclose(a.reactions[group], b.reactions[group], rtol=1e-12, atol=0)
    if comm.rank == 0:
        _, rows = read_csv(shared_dir / "first" / "history.csv")
        assert len(rows) == 2
        summary = json.loads((shared_dir / "first" / "summary.json").read_text())
        assert summary["increments"] == 2 and summary["converged"] is False
