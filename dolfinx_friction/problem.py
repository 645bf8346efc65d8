"""The discrete problem: bodies, rigid obstacles, contact pairs and their system numbering.

Built once from a :class:`~dolfinx_friction.model.Scene`; the solver drives it.
Residual ``R(u) = K u - f_ext + f_contact(u)``; the Jacobian is the bulk
stiffness plus the contact tangents, filled into a matrix whose pattern holds
the couplings of the current contact elements.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx_friction import bulk, gmsh_io
from dolfinx_friction.assembly import CooPattern
from dolfinx_friction.contact.element import ContactParameters
from dolfinx_friction.contact.laws import Exponential, Law, Linear, Tabular
from dolfinx_friction.fields import BodyField, DofLayout, make_fields
from dolfinx_friction.interaction import ContactInteraction, RigidMaster
from dolfinx_friction.model import ContactPair, Scene
from dolfinx_friction.surfaces import SlaveNodes, master_faces


class ModelError(ValueError):
    """The scene does not fit its mesh (a missing group, a group of the wrong kind...)."""


def make_law(pair: ContactPair) -> Law:
    if pair.law == "exponential":
        return Exponential(pair.c0, pair.p0)
    if pair.law == "tabular":
        p, d = zip(*pair.table)
        return Tabular(tuple(p), tuple(d))
    return Linear(pair.K, pair.sigma_inf, pair.c0)


@dataclass
class Timers:
    """Wall time per phase, seconds."""

    phases: dict = field(default_factory=lambda: dict.fromkeys(
        ["setup", "contact_search", "contact_assembly", "bulk_assembly", "linear_solve",
         "output"], 0.0))

    def add(self, phase: str, seconds: float) -> None:
        self.phases[phase] += seconds


class ContactProblem:
    """Everything the Newton solver needs, in system numbering."""

    def __init__(self, scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD,
                 meshes: Optional[gmsh_io.MeshSet] = None):
        self.scene, self.comm = scene, comm
        names = [b.name for b in scene.bodies]
        self.meshes = meshes or gmsh_io.load_mesh(scene.mesh, names, comm)
        self.gdim = self.meshes.gdim
        self._check_groups()
        self.fields, self.layout = make_fields(
            comm, [(b, self.meshes.bodies[b.name]) for b in scene.bodies], len(scene.rigids))
        d = self.gdim
        n_local = self.layout.n_owned * d
        self.u = PETSc.Vec().createMPI((n_local, PETSc.DETERMINE), comm=comm)
        self.u.set(0.0)
        entries = [bulk.stiffness_entries(f, self.layout) for f in self.fields]
        rows, cols, vals = (np.concatenate([e[k] for e in entries]) for k in range(3))
        self.bulk_pattern = CooPattern(comm, n_local, [(rows, cols)])
        self.bulk_data = self.bulk_pattern.gather_values(0, vals)  # CSR values
        self.K_bulk = self.bulk_pattern.create_matrix()
        self.bulk_pattern.fill(self.K_bulk, self.bulk_data)
        self.interactions = [self._interaction(k, c) for k, c in enumerate(scene.contacts)]

    # ------------------------------------------------------------ lookups
    def _check_groups(self) -> None:
        s, dims = self.scene, self.meshes.group_dims
        fdim = self.gdim - 1
        for i, r in enumerate(s.rigids):
            if r.name in dims:
                raise ModelError(f"rigid.{i}.name: {r.name!r} is also a physical group of the "
                                 "mesh: ambiguous as a contact master (rename the obstacle)")
        for k, c in enumerate(s.contacts):
            if c.slave not in dims:
                raise ModelError(f"contact.{k}.slave: no physical group {c.slave!r} in the mesh")
            if dims[c.slave] != fdim:
                raise ModelError(f"contact.{k}.slave: group {c.slave!r} has dimension "
                                 f"{dims[c.slave]}, contact surfaces need {fdim}")
            if s.rigid(c.master) is None:
                if c.master not in dims:
                    raise ModelError(f"contact.{k}.master: {c.master!r} is neither a physical "
                                     f"group of the mesh nor a [[rigid]] obstacle")
                if dims[c.master] != fdim:
                    raise ModelError(f"contact.{k}.master: group {c.master!r} has dimension "
                                     f"{dims[c.master]}, contact surfaces need {fdim}")
            for role in ("slave", "master"):
                g = getattr(c, role)
                if g not in dims:
                    continue
                owners = self.meshes.group_bodies.get(g, ())
                if len(owners) != 1:
                    touched = self.meshes.group_touches.get(g, ())
                    raise ModelError(
                        f"contact.{k}.{role}: group {g!r} " + (
                            f"lies on {len(owners)} bodies at once ({', '.join(owners)}: "
                            "their meshes share its nodes)" if owners else
                            f"spans the bodies {', '.join(touched)}" if len(touched) > 1 else
                            "lies on none of the bodies") +
                        "; a contact surface must lie on exactly one body")
                inside = self.meshes.bodies[owners[0]].interior_facets(g)
                if inside:
                    raise ModelError(f"contact.{k}.{role}: group {g!r} has {inside} facet(s) "
                                     f"inside body {owners[0]!r}; a contact surface must be on "
                                     "the body's boundary")
        for i, step in enumerate(s.steps):
            for j, bc in enumerate(step.bcs):
                self._check_node_group(bc.on, f"step.{i}.bc.{j}.on")
            for j, load in enumerate(step.loads):
                self._check_node_group(load.on, f"step.{i}.load.{j}.on")
                if dims[load.on] != fdim:
                    raise ModelError(f"step.{i}.load.{j}.on: group {load.on!r} is not a facet "
                                     f"group")
        for g in s.output.reactions or ():
            self._check_node_group(g, "output.reactions")
        wrong = [(key, v) for key, v in _vectors(s) if len(v) != self.gdim]
        if wrong:
            key, v = wrong[0]
            raise ModelError(f"{key} has {len(v)} components, but the mesh {s.mesh} is "
                             f"{self.gdim}D (every vector has the mesh dimension)")
        for b in s.bodies:
            if self.gdim == 3 and (b.plane != "strain" or b.thickness != 1.0):
                raise ModelError(f"body {b.name!r}: plane/thickness apply to 2D meshes only")

    def _check_node_group(self, group: str, key: str) -> None:
        if group not in self.meshes.group_dims:
            raise ModelError(f"{key}: no physical group {group!r} in the mesh")
        if not self.meshes.group_bodies.get(group):
            raise ModelError(f"{key}: group {group!r} lies on no deformable body")

    def body_field(self, name: str) -> BodyField:
        return next(f for f in self.fields if f.body.name == name)

    def group_fields(self, group: str) -> list[BodyField]:
        return [self.body_field(b) for b in self.meshes.group_bodies.get(group, ())]

    def rigid_node(self, name: str) -> int:
        return self.layout.rigid_node([r.name for r in self.scene.rigids].index(name))

    def owned_group_dofs(self, group: str) -> np.ndarray:
        """Local (rank-owned) system dof rows of every node of a group, (n_nodes, gdim)."""
        d = self.gdim
        rows = [(self.layout.block_offsets[f.block] + f.owned_group_nodes(group))[:, None] * d
                + np.arange(d) for f in self.group_fields(group)]
        return np.concatenate(rows) if rows else np.zeros((0, d), dtype=np.int64)

    def rigid_dofs(self, name: str) -> np.ndarray:
        """Local system dof rows of a rigid obstacle's translation (rank 0; empty elsewhere)."""
        if self.comm.rank != 0:
            return np.zeros((0, self.gdim), dtype=np.int64)
        node = self.rigid_node(name) - self.layout.start
        return (node * self.gdim + np.arange(self.gdim))[None]

    def rigid_body_modes(self) -> PETSc.NullSpace:
        """Translations and rotations of all bodies together, orthonormal (collective): the
        near null space that algebraic multigrid (GAMG) needs for elasticity.  Each body
        gets the rigid motions of its own nodes; a rigid obstacle only translates."""
        d = self.gdim
        modes = [self.u.duplicate() for _ in range(3 if d == 2 else 6)]
        values = np.zeros((len(modes), self.u.getLocalSize() // d, d))
        for f in self.fields:
            nodes = slice(int(self.layout.block_offsets[f.block]),
                          int(self.layout.block_offsets[f.block + 1]))
            x = f.X[: f.n_owned]
            values[:d, nodes] = np.eye(d)[:, None, :]
            for k, (i, j) in enumerate([(0, 1)] if d == 2 else [(0, 1), (1, 2), (2, 0)]):
                values[d + k, nodes, i], values[d + k, nodes, j] = -x[:, j], x[:, i]
        for r in self.scene.rigids:
            values[:d, self.rigid_dofs(r.name)[:, 0] // d] = np.eye(d)[:, None, :]
        for k, mode in enumerate(modes):  # modified Gram-Schmidt
            mode.setArray(values[k].ravel())
            for previous in modes[:k]:
                mode.axpy(-mode.dot(previous), previous)
            mode.scale(1.0 / mode.norm())
        return PETSc.NullSpace().create(vectors=modes, comm=self.comm)

    # ------------------------------------------------------------- contact
    def _interaction(self, k: int, pair: ContactPair) -> ContactInteraction:
        slave_field = self.group_fields(pair.slave)[0]
        pair = pair.resolved(slave_field.body.E)
        params = ContactParameters(make_law(pair), pair.mu, pair.stick_slope, pair.tangent)
        slaves = SlaveNodes(slave_field, pair.slave)
        rigid = self.scene.rigid(pair.master)
        if rigid is not None:
            master = RigidMaster(rigid, self.rigid_node(rigid.name))
        else:
            master = master_faces(self.group_fields(pair.master)[0], pair.master)
        return ContactInteraction(self.comm, f"{pair.slave}->{pair.master}", params, slaves,
                                  master, self.gdim, pair.pairing_iterations)

    def update_fields(self) -> None:
        """Copy the system displacement into the bodies' dolfinx Functions (ghosts included)."""
        from dolfinx_friction import compat
        local = self.u.getArray(readonly=True)
        for f in self.fields:
            n = f.n_owned * self.gdim
            f.u.x.array[:n] = local[self.layout.owned_slice(f.block, self.gdim)]
            compat.scatter_forward(f.u)

    def master_displacements(self, k: int) -> Optional[np.ndarray]:
        """Current displacement at the nodes of this rank's own master faces of pair ``k``."""
        inter = self.interactions[k]
        if inter.rigid:
            return None
        f = self.group_fields(self.scene.contacts[k].master)[0]
        return f.u.x.array.reshape(-1, self.gdim)[inter.master.local]


def _vectors(scene: Scene) -> list[tuple[str, tuple]]:
    """Every vector of the scene with its key path (arrays indexed from 0)."""
    out = []
    for i, step in enumerate(scene.steps):
        out += [(f"step.{i}.bc.{j}.u", bc.u) for j, bc in enumerate(step.bcs)]
        out += [(f"step.{i}.load.{j}.traction", ld.traction) for j, ld in enumerate(step.loads)
                if ld.traction is not None]
        for j, r in enumerate(step.rigid):
            name = "displacement" if r.displacement is not None else "force"
            out.append((f"step.{i}.rigid.{j}.{name}", getattr(r, name)))
    for i, r in enumerate(scene.rigids):
        out += [(f"rigid.{i}.{name}", getattr(r, name))
                for name in ("point", "normal", "center", "axis") if getattr(r, name) is not None]
    return out
