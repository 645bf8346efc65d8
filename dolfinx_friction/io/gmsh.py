"""Gmsh meshes -> one dolfinx mesh per deformable body.

The mesh is split into bodies by :mod:`dolfinx_friction.io.msh` (no dolfinx there).
Each body becomes its own :class:`dolfinx.mesh.Mesh` made only of its cells; every
other named physical group is given to each body that contains all of its nodes, as
local entity indices of that body's mesh.

Gmsh is only used on rank 0; the other ranks pass empty arrays to
``create_mesh`` and ``distribute_entity_data``, like dolfinx's own
``gmshio.model_to_mesh``.  Errors are decided on rank 0 and broadcast, so
every rank raises the same :class:`MeshError`.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional, Sequence, Union

import numpy as np
from mpi4py import MPI

import dolfinx
import dolfinx.mesh

from dolfinx_friction import _compat as compat
from dolfinx_friction.fem.tagged_mesh import BodyMesh
from dolfinx_friction.io.msh import (_BODY_TYPES, _ENTITY_TYPES, MeshError, MeshSplit,
                                     SplitBody, read_split)

__all__ = ["MeshError", "BodyMesh", "MeshSet", "load_mesh"]


# --------------------------------------------------------------------------
# Public data classes
# --------------------------------------------------------------------------
@dataclass
class MeshSet:
    """All bodies of a Gmsh mesh.

    ``group_dims``: every named physical group -> its dimension.
    ``group_bodies``: every named group -> the bodies whose nodes contain all
    of its nodes (a body's own group -> ``(body,)``; a group that no single
    body contains, or a cell group that is not a body -> ``()``).  Both are
    the same on all ranks.
    """

    gdim: int
    bodies: dict[str, BodyMesh]
    group_dims: dict[str, int]
    group_bodies: dict[str, tuple[str, ...]]
    #: every named group -> the bodies that hold at least one of its nodes
    group_touches: dict[str, tuple[str, ...]] = field(default_factory=dict)


# --------------------------------------------------------------------------
# --------------------------------------------------------------------------
# Building the dolfinx meshes (all ranks)
# --------------------------------------------------------------------------
def _build_body(comm, plan: SplitBody, gdim: int, root: bool) -> BodyMesh:
    shape, nn = _BODY_TYPES[plan.gmsh_type]
    cell_type = getattr(dolfinx.mesh.CellType, shape)
    if root:
        cells, x = plan.cells, plan.x
    else:
        cells, x = np.zeros((0, nn), np.int64), np.zeros((0, gdim), np.float64)
    cells = cells[:, compat.cell_perm_gmsh(cell_type, nn)]
    domain = compat.ufl_mesh(plan.gmsh_type, gdim)
    mesh = compat.create_mesh(comm, cells, x, domain)
    mesh.name = plan.name
    topology = mesh.topology
    tdim = topology.dim

    groups: dict[str, tuple[int, np.ndarray]] = {}
    num_cells = topology.index_map(tdim).size_local + topology.index_map(tdim).num_ghosts
    groups[plan.name] = (tdim, np.arange(num_cells, dtype=np.int32))
    bad: list[str] = []
    for g in plan.groups:
        eshape, enn = _ENTITY_TYPES[g.gmsh_type]
        ents = g.entities if root else np.zeros((0, enn), np.int64)
        ents = ents[:, compat.cell_perm_gmsh(getattr(dolfinx.mesh.CellType, eshape), enn)]
        topology.create_entities(g.dim)
        topology.create_connectivity(g.dim, 0)
        topology.create_connectivity(g.dim, tdim)
        local, values = compat.distribute_entity_data(mesh, g.dim, ents,
                                                      np.ones(len(ents), dtype=np.int32))
        local = np.asarray(local, dtype=np.int32).reshape(-1, max(1, _num_vertices(eshape)))
        tags = compat.meshtags_from_entities(mesh, g.dim, local, np.asarray(values, np.int32))
        idx = np.unique(np.asarray(tags.indices, dtype=np.int32))
        groups[g.name] = (g.dim, idx)
        # Every element must have become an entity of the body mesh
        imap = topology.index_map(g.dim)
        owned = idx[idx < imap.size_local]
        found = comm.allreduce(len(owned), op=MPI.SUM)
        if found != g.count:
            bad.append(f"group '{g.name}': {found} of its {g.count} elements found as "
                       f"{g.dim}-entities of body '{plan.name}'")
    if bad:
        raise MeshError("; ".join(bad))
    return BodyMesh(plan.name, mesh, groups)


def _num_vertices(shape: str) -> int:
    return {"point": 1, "interval": 2, "triangle": 3, "quadrilateral": 4,
            "tetrahedron": 4, "hexahedron": 8}[shape]


def load_mesh(source: Union[str, Path, Any], body_names: Sequence[str],
              comm: MPI.Comm = MPI.COMM_WORLD) -> MeshSet:
    """Read a Gmsh mesh into one dolfinx mesh per body.

    ``source``: a ``.msh`` file (format 2.2 or 4.1) or the ``gmsh`` module
    with the live, meshed model (its current model; read on rank 0 only, gmsh
    is left initialized).  ``body_names``: the physical groups of cells that
    are bodies.  Collective on ``comm``; raises :class:`MeshError` on all
    ranks for a missing/unreadable file, no named groups, an unknown body
    name, a body group of the wrong dimension, an empty group, mixed or
    unsupported cell types, or non-planar 2D meshes.
    """
    body_names = [str(b) for b in ([body_names] if isinstance(body_names, str) else body_names)]
    is_file = isinstance(source, (str, os.PathLike))
    if not is_file and not (hasattr(source, "model") and hasattr(source, "merge")):
        raise TypeError("load_mesh: source must be a path or the gmsh module, "
                        f"not {type(source)!r}")
    root = comm.rank == 0
    plan: Optional[MeshSplit] = None
    message: Any = None
    if root:
        try:
            plan = read_split(source, body_names)
        except MeshError as e:
            message = ("mesh", str(e))
        except Exception as e:
            message = ("internal", f"{type(e).__name__}: {e}")
            comm.bcast((message, None), root=0)
            raise
        meta = None if plan is None else MeshSplit(plan.gdim, [b.strip() for b in plan.bodies],
                                                   plan.group_dims, plan.group_bodies,
                                                   plan.group_touches)
        comm.bcast((message, meta), root=0)
    else:
        message, plan = comm.bcast(None, root=0)
    if message is not None:
        kind, text = message
        if kind == "mesh":
            raise MeshError(text)
        raise RuntimeError(f"reading the mesh failed on rank 0: {text}")
    assert plan is not None

    bodies = {bp.name: _build_body(comm, bp, plan.gdim, root) for bp in plan.bodies}
    # every group of a body is listed on every rank (possibly empty)
    return MeshSet(plan.gdim, bodies, dict(plan.group_dims), dict(plan.group_bodies),
                   dict(plan.group_touches))
