"""What a run was: the scene as run, every default resolved, and its hash (summary.json).

The values are read from the objects the run used (the bodies' spaces, the contact pairs'
laws, the linear solver), never computed again from the defaults.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import asdict
from pathlib import Path
from typing import Optional

from dolfinx_friction import __version__

from dolfinx_friction import _compat as compat
from dolfinx_friction.nls.defaults import choose
from dolfinx_friction.nls.linear import LinearSolver
from dolfinx_friction.scene.build import ContactProblem


def canonical_json(data) -> str:
    """The canonical serialisation that ``scene_sha256`` hashes: JSON with sorted keys and
    no spaces (paths as strings)."""
    return json.dumps(data, sort_keys=True, separators=(",", ":"), default=str)


def file_sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def resolved_scene(problem: ContactProblem, reaction_groups: list[str],
                   linear: Optional[LinearSolver]) -> dict:
    """The scene as run: per body its model, E, nu, degree...; per contact pair its law
    with every parameter, mu, stick slope, tangent and pairing iterations; the steps with
    their solver settings; the linear solver (None if no system was solved); the mesh
    file and its hash."""
    scene = problem.scene
    mesh = scene.mesh
    if isinstance(mesh, (str, Path)):
        mesh = {"file": str(mesh), "sha256": file_sha256(Path(mesh))}
    else:
        mesh = {"file": None, "sha256": None}  # a live gmsh model
    return {
        "title": scene.title,
        "mesh": mesh,
        "bodies": [{**asdict(f.body), "degree": compat.space_degree(f.V)}
                   for f in problem.fields],
        "rigids": [asdict(r) for r in scene.rigids],
        "contacts": [{"slave": c.slave, "master": c.master, **problem.pair_of(c).resolved()}
                     for c in scene.contacts],
        "steps": [asdict(s) for s in scene.steps],
        "output": {"reactions": list(reaction_groups), "fields": scene.output.fields,
                   "contact_table": scene.output.contact_table},
        "solver": {**asdict(scene.solver), "petsc_options": dict(scene.solver.petsc_options),
                   "dofs": problem.system.x.getSize(),
                   "chosen": choose(scene.solver.linear, problem.system.x.getSize(),
                                    problem.gdim, scene.solver.direct_max_dofs)},
        "linear_solver": linear.settings() if linear is not None else None,
    }


def provenance(problem: ContactProblem, reaction_groups: list[str],
               linear: Optional[LinearSolver]) -> dict:
    """``scene_sha256`` (of :func:`canonical_json` of ``resolved``), ``resolved``
    (:func:`resolved_scene`) and ``package_version``, for summary.json."""
    resolved = json.loads(canonical_json(resolved_scene(problem, reaction_groups, linear)))
    return {"package_version": __version__,
            "scene_sha256": hashlib.sha256(canonical_json(resolved).encode()).hexdigest(),
            "resolved": resolved}
