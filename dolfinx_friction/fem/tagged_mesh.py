"""A body's mesh with its named groups of entities (what a contact surface, a load or a
boundary condition is put on).

:class:`BodyMesh` is made by the Gmsh loader (:func:`dolfinx_friction.io.gmsh.load_mesh`,
one per body) and by :class:`~dolfinx_friction.NodeToSurface` around a user's mesh and
facet tags.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import dolfinx
import dolfinx.mesh
import numpy as np
from mpi4py import MPI

__all__ = ["BodyMesh"]


@dataclass
class BodyMesh:
    """One deformable body: its own mesh and the named groups it contains.

    ``groups`` maps a group name to ``(entity dim, local entity indices)`` on
    this rank (int32, sorted, unique, possibly empty).  Indices are local
    indices of the body mesh's entities of that dimension and include every
    entity this rank holds (owned or not).  The body's own group is there
    too, as all local cells.
    """

    name: str
    mesh: dolfinx.mesh.Mesh
    groups: dict[str, tuple[int, np.ndarray]] = field(default_factory=dict)

    def meshtags(self, dim: int, names: Sequence[str]) -> tuple[Any, dict[str, int]]:
        """MeshTags of dimension ``dim`` with value ``i + 1`` on ``names[i]``.

        Returns ``(tags, {name: value})``; use e.g.
        ``ufl.Measure("ds", domain=body.mesh, subdomain_data=tags)``.
        Collective (all ranks must call it): raises ``ValueError`` on every
        rank if the named groups overlap, ``KeyError`` for an unknown name and
        ``ValueError`` for a group of another dimension.
        """
        values: dict[str, int] = {}
        idx_parts, val_parts = [], []
        for i, name in enumerate(names):
            if name not in self.groups:
                raise KeyError(f"body '{self.name}' has no group '{name}' "
                               f"(it has: {', '.join(sorted(self.groups)) or 'none'})")
            gdim, idx = self.groups[name]
            if gdim != dim:
                raise ValueError(f"group '{name}' of body '{self.name}' has dimension {gdim}, "
                                 f"not {dim}")
            values[name] = i + 1
            idx_parts.append(np.asarray(idx, dtype=np.int32))
            val_parts.append(np.full(len(idx), i + 1, dtype=np.int32))
        idx = np.concatenate(idx_parts) if idx_parts else np.zeros(0, np.int32)
        val = np.concatenate(val_parts) if val_parts else np.zeros(0, np.int32)
        order = np.argsort(idx, kind="stable")
        idx, val = idx[order], val[order]
        overlap = bool(np.any(np.diff(idx) == 0))
        if self.mesh.comm.allreduce(overlap, op=MPI.LOR):
            raise ValueError(f"groups {list(names)} of body '{self.name}' overlap: "
                             "an entity can carry only one tag value")
        tags = dolfinx.mesh.meshtags(self.mesh, dim, idx, val)
        tags.name = f"{self.name}:" + ",".join(names)
        return tags, values

    def interior_facets(self, name: str) -> int:
        """How many facets of the facet group ``name`` are interior to this body (two
        cells), summed over the ranks.  Collective."""
        topology = self.mesh.topology
        fdim = topology.dim - 1
        topology.create_entities(fdim)
        topology.create_connectivity(fdim, topology.dim)
        exterior = dolfinx.mesh.exterior_facet_indices(topology)
        dim, idx = self.groups[name]
        owned = idx[idx < topology.index_map(dim).size_local]
        inside = int(np.count_nonzero(~np.isin(owned, exterior)))
        return self.mesh.comm.allreduce(inside, op=MPI.SUM)
