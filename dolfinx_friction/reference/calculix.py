"""A scene as a CalculiX input deck, and reactions read back from ``ccx``.

:func:`write_inp` turns a :class:`~dolfinx_friction.scene.model.Scene` into an
input deck for CalculiX CrunchiX (tested with 2.20, Debian ``calculix-ccx``)
that models the same problem as dolfinx_friction:

* the mesh is split into bodies as for our own runs (:mod:`dolfinx_friction.io.msh`):
  every body gets its own copy of its nodes, so bodies never share nodes;
  first-order hexahedra become ``C3D8`` and tetrahedra ``C3D4``;
* one element set, material and ``*SOLID SECTION`` per body: ``*ELASTIC`` with
  E and nu for ``model = "linear"`` and ``"saint-venant-kirchhoff"``,
  ``*HYPERELASTIC, NEO HOOKE`` with ``C10 = mu/2``, ``D1 = 2/kappa`` for
  ``"neo-hookean"``;
* finite strain: if any body has a finite-strain model, every ``*STEP`` is
  ``NLGEOM`` (Green-Lagrange strain and second Piola-Kirchhoff stress with
  ``*ELASTIC``: Saint Venant-Kirchhoff).  CalculiX applies NLGEOM to the whole
  model, so a ``"linear"`` body of such a scene is Saint Venant-Kirchhoff in
  the deck (the deck says so in a comment); for a stiff linear body (a
  foundation, a die) the two differ by its squared strains only.  A scene
  without finite-strain bodies is written as before, without NLGEOM;
* a node set for every group that carries a bc or a reaction, made of the
  group's nodes in every body that contains all of them;
* an element-face surface (``TYPE=ELEMENT``) for the slave and the master
  group of every contact pair.  The slave surface must be face based: from
  its faces CalculiX computes the representative areas ``A_p`` (a node-based
  slave surface has none, docs/theory.md §2.1);
* ``*CONTACT PAIR, TYPE=NODE TO SURFACE`` (without ``SMALL SLIDING`` CalculiX
  re-pairs in every iteration up to the 8th, as our default
  ``pairing_iterations = 8``; ``pairing_iterations = 1`` becomes ``SMALL
  SLIDING``) with a ``*SURFACE INTERACTION`` whose law parameters are those
  of :meth:`ContactPair.resolved` (``K``, ``sigma_inf``, ``c0``; ``mu``,
  ``lambda``; the default ``K`` and ``lambda`` with :func:`slave_spacing`), always
  written explicitly (CalculiX's own defaults come from
  the first material of the deck, ours from the slave body);
* one ``*STEP`` per scene step, ``*STATIC, DIRECT`` with the scene's number of
  equal increments (``automatic=True``: ``*STATIC``, CalculiX's automatic
  incrementation, starting at and never above that size).  In a ``*STATIC`` step
  CalculiX ramps boundary values and loads linearly from their values at the end
  of the previous step to the new totals, and they persist into later steps, as
  in the scene (checked: the reactions agree increment by increment with a
  2-increment press);
* ``*NODE PRINT, TOTALS=ONLY`` of ``RF`` on every reaction group: the sum of
  the reaction forces, the same quantity and sign as our reactions -- except
  where a load acts on constrained nodes: CalculiX's ``RF`` is the internal
  force at the constrained dofs and leaves such loads out, ours is internal
  minus external force;
* ``*CONTROLS, PARAMETERS=FIELD`` tightened (:data:`DEFAULT_FIELD_CONTROLS`)
  so that CalculiX iterates to a residual comparable with our Newton
  tolerance.  Surface loads: a pressure becomes ``*DLOAD`` ``Pn`` on the
  element faces, a traction consistent nodal forces (``*CLOAD``).

Where the two codes still differ (reference vs. deformed ``A_p``, pairing near
master face edges) is measured and explained in
``tests/verification/test_calculix.py``; at finite strain (NLGEOM, Neo-Hookean
bodies) in ``tests/verification/test_calculix_nlgeom.py``.

:func:`run_ccx` runs ``ccx`` on a deck and returns the reaction sums per step
and increment.  Rigid obstacles, 2D meshes and second-order elements are not
translated (:class:`NotImplementedError`).
"""
from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional, Sequence, Union

import numpy as np

from dolfinx_friction.contact.shapes import FACE_TYPES, face_areas
from dolfinx_friction.fem.materials import bulk_modulus, lame
from dolfinx_friction.io.msh import GMSH_NAMES, MeshSplit, read_split
from dolfinx_friction.scene.model import MODELS, Body, ContactPair, Scene

__all__ = ["CCX_FACES", "CcxError", "CcxRun", "ccx_available", "ccx_executable", "read_dat",
           "read_mesh", "run_ccx", "slave_spacing", "write_inp", "DEFAULT_FIELD_CONTROLS"]

#: CalculiX face numbering (``S1``...) of its elements as 0-based local nodes,
#: from the ``ifaceq``/``ifacet`` tables of the CalculiX sources (the node
#: *sets* matter here; CalculiX orders them so that the normal points out).
CCX_FACES: dict[str, tuple[tuple[int, ...], ...]] = {
    "C3D8": ((0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)),
    "C3D4": ((0, 1, 2), (0, 1, 3), (1, 2, 3), (0, 2, 3)),
}
# Gmsh element type -> CalculiX element; Gmsh's node order is CalculiX's for both.
_CELLS = {5: "C3D8", 4: "C3D4"}
# node permutation that flips the orientation of a cell (negative Jacobian)
_FLIP = {"C3D8": [0, 3, 2, 1, 4, 7, 6, 5], "C3D4": [0, 2, 1, 3]}

#: ``*CONTROLS, PARAMETERS=FIELD`` written by default: CalculiX's own criteria
#: (largest residual below 0.5 % of the average force, largest correction
#: below 1 % of the incremental solution) are far looser than our Newton
#: tolerance; these make CalculiX iterate to a residual that is negligible at
#: the 1e-4 level of the reactions.  Order: R_n, C_n, q_0, q_u, R_p, eps, C_eps, R_l.
DEFAULT_FIELD_CONTROLS: tuple[Optional[float], ...] = (1e-7, 1e-6, None, None, 1e-7, 1e-5,
                                                       1e-6, 1e-8)


class CcxError(RuntimeError):
    """``ccx`` failed or its output could not be read; the message quotes its log."""


# --------------------------------------------------------------------------- the mesh


@dataclass
class CcxBody:
    name: str
    etype: str  # "C3D8" | "C3D4"
    elements: np.ndarray  # (n,) CalculiX element numbers
    cells: np.ndarray  # (n, nn) CalculiX node numbers, CalculiX order, positive volume
    nodes: np.ndarray  # (m,) CalculiX node numbers of the body (sorted)


@dataclass
class CcxMesh:
    """The scene's mesh in CalculiX numbering (1-based; node ``i`` is ``x[i - 1]``)."""

    x: np.ndarray  # (n_nodes, 3)
    bodies: dict[str, CcxBody]
    #: group name -> (dim, [(body, (n, k) CalculiX node numbers of each group element)])
    groups: dict[str, tuple[int, list[tuple[str, np.ndarray]]]] = field(default_factory=dict)

    def group_nodes(self, name: str) -> np.ndarray:
        """CalculiX node numbers of a group, in every body that contains all of its nodes."""
        _, parts = self._group(name)
        if not parts:
            raise ValueError(f"group {name!r} lies on no body")
        return np.unique(np.concatenate([p.ravel() for _, p in parts]))

    def surface(self, name: str) -> list[tuple[int, int]]:
        """``(element, face number)`` of every facet of a facet group on exactly one body."""
        dim, parts = self._group(name)
        if dim != 2:
            raise ValueError(f"group {name!r} has dimension {dim}; surfaces need facets (2)")
        if len(parts) != 1:
            raise ValueError(f"group {name!r} must lie on exactly one body, found "
                             f"{[b for b, _ in parts]}")
        body_name, facets = parts[0]
        body = self.bodies[body_name]
        lookup = _face_lookup(body)
        out = []
        for row in facets:
            key = tuple(sorted(int(n) for n in row))
            if key not in lookup:
                raise ValueError(f"a facet of group {name!r} (nodes {list(row)}) is no face of "
                                 f"an element of body {body_name!r}")
            out.append(lookup[key])
        return out

    def _group(self, name: str):
        if name not in self.groups:
            raise ValueError(f"no physical group {name!r} in the mesh "
                             f"(available: {', '.join(sorted(self.groups))})")
        return self.groups[name]


def _face_lookup(body: CcxBody) -> dict[tuple[int, ...], tuple[int, int]]:
    """Sorted face nodes -> (element, CalculiX face number) for the faces of a body."""
    lookup: dict[tuple[int, ...], tuple[int, int]] = {}
    for k, local in enumerate(CCX_FACES[body.etype]):
        faces = np.sort(body.cells[:, list(local)], axis=1)
        for elem, face in zip(body.elements, faces):
            lookup.setdefault(tuple(int(n) for n in face), (int(elem), k + 1))
    return lookup


def _orient(etype: str, cells: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Reorder cells with a negative Jacobian at their centre (CalculiX rejects them)."""
    p = x[cells - 1]
    if etype == "C3D4":
        J = np.stack([p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]], axis=2)
    else:  # trilinear hexahedron at its centre
        J = np.stack([(p[:, [1, 2, 5, 6]] - p[:, [0, 3, 4, 7]]).mean(1),
                      (p[:, [2, 3, 6, 7]] - p[:, [1, 0, 5, 4]]).mean(1),
                      (p[:, [4, 5, 6, 7]] - p[:, [0, 1, 2, 3]]).mean(1)], axis=2)
    flip = np.linalg.det(J) < 0.0
    cells = cells.copy()
    cells[flip] = cells[flip][:, _FLIP[etype]]
    return cells


def _numbered(split: MeshSplit, where: str) -> CcxMesh:
    """The bodies of a split mesh in CalculiX numbering: nodes body after body (each body
    its own copy, as in our meshes), cells oriented; every group on every body that holds
    all of its nodes, facet groups as their facets, other groups as their nodes."""
    xs, bodies = [], {}
    n_nodes, n_elems = 0, 0
    for body in split.bodies:
        if split.gdim != 3:
            raise NotImplementedError(f"{where}: body {body.name!r} is {split.gdim}D; the "
                                      "CalculiX export handles 3D solids only")
        if body.gmsh_type not in _CELLS:
            raise NotImplementedError(f"{where}: body {body.name!r} has "
                                      f"{GMSH_NAMES.get(body.gmsh_type, body.gmsh_type)} cells; "
                                      "the CalculiX export handles first-order hexahedra "
                                      "(C3D8) and tetrahedra (C3D4) only")
        etype = _CELLS[body.gmsh_type]
        xs.append(body.x)
        numbers = n_nodes + 1 + np.arange(len(body.x))
        cells = _orient(etype, numbers[body.cells], np.concatenate(xs))
        bodies[body.name] = CcxBody(body.name, etype, n_elems + 1 + np.arange(len(cells)),
                                    cells, numbers)
        n_nodes += len(body.x)
        n_elems += len(cells)
    x = np.concatenate(xs) if xs else np.zeros((0, 3))
    parts: dict[str, dict[str, list[np.ndarray]]] = {name: {} for name in split.group_dims}
    for body in split.bodies:
        numbers = bodies[body.name].nodes
        parts[body.name][body.name] = [np.arange(len(numbers))]
        for g in body.groups:
            parts[g.name].setdefault(body.name, []).append(g.entities)
    groups: dict[str, tuple[int, list[tuple[str, np.ndarray]]]] = {}
    for name, on in parts.items():
        dim = split.group_dims[name]
        groups[name] = (dim, [
            (b, bodies[b].nodes[np.concatenate(ents)] if dim == 2 else
             bodies[b].nodes[np.unique(np.concatenate(ents))][:, None]) for b, ents in on.items()])
    return CcxMesh(x, bodies, groups)


def read_mesh(source: Union[str, Path, Any], body_names: Sequence[str]) -> CcxMesh:
    """Read a Gmsh mesh (a ``.msh`` file or the live ``gmsh`` module) in CalculiX numbering;
    :class:`~dolfinx_friction.io.msh.MeshError` (a ValueError) for a mesh that
    :func:`~dolfinx_friction.io.gmsh.load_mesh` refuses too."""
    where = (f"mesh file '{source}'" if isinstance(source, (str, os.PathLike)) else
             f"gmsh model '{source.model.getCurrent()}'")
    return _numbered(read_split(source, body_names), where)


# --------------------------------------------------------------------------- the deck


class _Names:
    """CalculiX names (upper case, [A-Z0-9_], <= 80 characters, unique) for our names."""

    def __init__(self):
        self.used: dict[str, str] = {}

    def __call__(self, prefix: str, name: str) -> str:
        key = f"{prefix}:{name}"
        if key not in self.used:
            base = (prefix + "_" + re.sub(r"[^A-Z0-9_]", "_", name.upper()))[:72]
            candidate, i = base, 1
            while candidate in self.used.values():
                i += 1
                candidate = f"{base}_{i}"
            self.used[key] = candidate
        return self.used[key]


#: CalculiX reads a number from the first 20 characters of its field and ignores the rest
FIELD_WIDTH = 20
#: the smallest increment CalculiX's automatic incrementation may cut back to, as a share
#: of the scene's (``write_inp(automatic=True)``)
MIN_INCREMENT = 1e-4


def _num(v: float) -> str:
    """``v`` in at most :data:`FIELD_WIDTH` characters: its shortest repr, else as many
    significant digits as fit (``7.959123334089213e-05`` would be read as 7.959)."""
    text, digits = repr(float(v)), 17
    while len(text) > FIELD_WIDTH:
        digits -= 1
        text = f"{float(v):.{digits}g}"
    return text


def _id_lines(ids: Sequence[int], per_line: int = 16) -> list[str]:
    ids = [int(i) for i in ids]
    return [", ".join(str(i) for i in ids[k:k + per_line]) for k in range(0, len(ids), per_line)]


def _traction_forces(mesh: CcxMesh, group: str) -> tuple[np.ndarray, np.ndarray]:
    """Nodes of a facet group and their consistent force per unit traction (= nodal areas)."""
    _, parts = mesh._group(group)
    nodes, weights = [], []
    for _, facets in parts:
        for row in facets:
            p = mesh.x[row - 1]
            if len(row) == 3:
                area = 0.5 * np.linalg.norm(np.cross(p[1] - p[0], p[2] - p[0]))
                w = np.full(3, area / 3.0)
            else:  # bilinear quadrilateral, 2x2 Gauss
                w = np.zeros(4)
                g = 1.0 / math.sqrt(3.0)
                for xi in (-g, g):
                    for eta in (-g, g):
                        phi = 0.25 * np.array([(1 - xi) * (1 - eta), (1 + xi) * (1 - eta),
                                               (1 + xi) * (1 + eta), (1 - xi) * (1 + eta)])
                        dxi = 0.25 * np.array([-(1 - eta), 1 - eta, 1 + eta, -(1 + eta)])
                        deta = 0.25 * np.array([-(1 - xi), -(1 + xi), 1 + xi, 1 - xi])
                        w += phi * np.linalg.norm(np.cross(dxi @ p, deta @ p))
            nodes.append(row)
            weights.append(w)
    if not nodes:
        return np.zeros(0, int), np.zeros(0)
    nodes_a, weights_a = np.concatenate(nodes), np.concatenate(weights)
    uniq, inv = np.unique(nodes_a, return_inverse=True)
    return uniq, np.bincount(inv, weights=weights_a)


def slave_spacing(mesh: CcxMesh, group: str) -> float:
    """The node spacing h of a slave facet group, as :attr:`NodeToSurface.spacing` finds it
    (the median over the group's nodes of the square root of each node's share
    ``sum_f w_p,f A_f`` of the face areas): what the default ``K`` and ``stick_slope``
    scale with."""
    _, parts = mesh._group(group)
    faces = np.concatenate([p for _, p in parts]).astype(np.int64)
    # Gmsh orders a quadrilateral's nodes around it, the Q4 face type as a tensor product
    face, order = (FACE_TYPES["Q4"], [0, 1, 3, 2]) if faces.shape[1] == 4 else \
        (FACE_TYPES["T3"], [0, 1, 2])
    faces = faces[:, order]
    shares = face_areas(face, mesh.x[faces - 1])[:, None] * np.asarray(face.area_weights)
    area = np.bincount(faces.ravel(), weights=shares.ravel())[np.unique(faces)]
    return float(np.median(np.sqrt(area)))


def _interaction_lines(name: str, pair: ContactPair) -> list[str]:
    lines = [f"*SURFACE INTERACTION, NAME={name}"]
    if pair.law == "linear":
        lines += ["*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR",
                  f"{_num(pair.K)}, {_num(pair.sigma_inf)}, {_num(pair.c0)}"]
    elif pair.law == "exponential":
        lines += ["*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=EXPONENTIAL",
                  f"{_num(pair.c0)}, {_num(pair.p0)}"]
    elif pair.law == "tabular":
        lines += ["*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=TABULAR"]
        lines += [f"{_num(p)}, {_num(d)}" for p, d in pair.table]
    else:  # pragma: no cover - resolved() maps hard to linear
        raise NotImplementedError(f"law {pair.law!r}")
    if pair.mu > 0.0:
        lines += ["*FRICTION", f"{_num(pair.mu)}, {_num(pair.stick_slope)}"]
    return lines


def _material_lines(body: Body) -> list[str]:
    """The material cards of a body: ``*ELASTIC`` (linear and Saint Venant-Kirchhoff: the
    latter is what CalculiX does with ``*ELASTIC`` in an NLGEOM step) or ``*HYPERELASTIC,
    NEO HOOKE`` with ``C10 = mu/2``, ``D1 = 2/kappa`` (as :func:`problem.strain_energy`)."""
    if body.model == "neo-hookean":
        if not body.nu < 0.5:
            raise ValueError(f"body {body.name!r}: nu = {body.nu} >= 0.5 for the compressible "
                             "Neo-Hookean model")
        _, mu = lame(body.E, body.nu)
        kappa = bulk_modulus(body.E, body.nu)
        return ["*HYPERELASTIC, NEO HOOKE", f"{_num(0.5 * mu)}, {_num(2.0 / kappa)}"]
    return ["*ELASTIC", f"{_num(body.E)}, {_num(body.nu)}"]


def write_inp(scene: Scene, path: Union[str, Path], *,
              field_controls: Optional[Sequence[Optional[float]]] = DEFAULT_FIELD_CONTROLS,
              time_controls: Optional[Sequence[Optional[float]]] = None,
              mesh: Optional[CcxMesh] = None, automatic: bool = False) -> CcxMesh:
    """Write ``scene`` as a CalculiX input deck at ``path``; return the mesh as numbered there.

    ``field_controls``: the values of ``*CONTROLS, PARAMETERS=FIELD`` written in
    every step (``None`` entries keep CalculiX's default; ``field_controls=None``
    writes no card).  ``time_controls``: optional first line of
    ``*CONTROLS, PARAMETERS=TIME INCREMENTATION``.  ``automatic``: CalculiX cuts an
    increment back where it does not converge (its increments then end at other times than
    the scene's; :attr:`CcxRun.times`), instead of stopping.  Raises
    :class:`NotImplementedError` for what has no CalculiX counterpart here
    (rigid obstacles, 2D, second-order cells, a component released after being
    prescribed) and :class:`ValueError` for groups the mesh does not have.
    """
    path = Path(path)
    for b in scene.bodies:
        if b.model not in MODELS:
            raise ValueError(f"body {b.name!r}: unknown model {b.model!r} (one of "
                             f"{', '.join(MODELS)})")
    nlgeom = any(b.finite_strain for b in scene.bodies)
    if scene.rigids:
        raise NotImplementedError("rigid obstacles ([[rigid]]) are not exported to CalculiX; "
                                  "mesh the obstacle as a body instead")
    for b in scene.bodies:
        if b.degree not in (None, 1):
            raise NotImplementedError(f"body {b.name!r}: degree {b.degree}; the CalculiX export "
                                      "handles first-order elements only")
    if mesh is None:
        mesh = read_mesh(scene.mesh, [b.name for b in scene.bodies])
    name = _Names()
    out: list[str] = [
        "** CalculiX input deck written by dolfinx_friction.reference.calculix",
        f"** scene: {scene.source or '(built in Python)'}",
    ]
    if scene.title:
        out.append(f"** title: {scene.title}")
    if nlgeom:
        linear = [b.name for b in scene.bodies if not b.finite_strain]
        out.append("** finite strain: every *STEP is NLGEOM" + (
            f"; CalculiX treats the linear bodies ({', '.join(linear)}) as Saint Venant-"
            "Kirchhoff there" if linear else ""))

    # ---- nodes and elements
    out.append("*NODE, NSET=NALL")
    out += [f"{i + 1}, {_num(p[0])}, {_num(p[1])}, {_num(p[2])}" for i, p in enumerate(mesh.x)]
    for body in mesh.bodies.values():
        out.append(f"*ELEMENT, TYPE={body.etype}, ELSET={name('E', body.name)}")
        out += [f"{e}, " + ", ".join(str(int(n)) for n in cell)
                for e, cell in zip(body.elements, body.cells)]

    # ---- node sets: bcs, loads and reactions
    reaction_groups = list(scene.output.reactions) if scene.output.reactions is not None else list(
        dict.fromkeys(bc.on for step in scene.steps for bc in step.bcs))
    node_groups = list(dict.fromkeys(
        [bc.on for step in scene.steps for bc in step.bcs] + reaction_groups))
    for g in node_groups:
        out.append(f"*NSET, NSET={name('N', g)}")
        out += _id_lines(mesh.group_nodes(g))
    for g in reaction_groups:
        out.append(f"** dolfinx_friction reaction {name('N', g)} {g}")

    # ---- materials and sections
    for b in scene.bodies:
        out += [f"*MATERIAL, NAME={name('M', b.name)}", *_material_lines(b),
                f"*SOLID SECTION, ELSET={name('E', b.name)}, MATERIAL={name('M', b.name)}"]

    # ---- contact
    for k, pair in enumerate(scene.contacts):
        slave_bodies = [b for b, _ in mesh._group(pair.slave)[1]]
        if len(slave_bodies) != 1:
            raise ValueError(f"contact.{k}.slave: group {pair.slave!r} must lie on exactly one "
                             f"body, found {slave_bodies}")
        resolved = pair.resolved(scene.body(slave_bodies[0]).E,
                                 slave_spacing(mesh, pair.slave))
        for role in (pair.slave, pair.master):
            surf = name("S", role)
            if not any(line == f"*SURFACE, NAME={surf}, TYPE=ELEMENT" for line in out):
                out.append(f"*SURFACE, NAME={surf}, TYPE=ELEMENT")
                out += [f"{e}, S{f}" for e, f in mesh.surface(role)]
        inter = name("SI", str(k))
        out += _interaction_lines(inter, resolved)
        # CalculiX re-pairs in iterations 1-8 by default; SMALL SLIDING pairs once
        # per increment.  Other pairing_iterations have no CalculiX counterpart.
        sliding = ", SMALL SLIDING" if pair.pairing_iterations == 1 else ""
        if pair.pairing_iterations not in (1, 8):
            out.append(f"** contact.{k}: pairing_iterations = {pair.pairing_iterations} has no "
                       "CalculiX counterpart (it re-pairs in iterations 1-8)")
        out += [f"*CONTACT PAIR, INTERACTION={inter}, TYPE=NODE TO SURFACE{sliding}",
                f"{name('S', pair.slave)}, {name('S', pair.master)}"]

    # ---- steps
    bc_state: dict[str, tuple] = {}
    cload_nodes: dict[int, np.ndarray] = {}  # every node ever loaded -> its current force
    load_state: dict[str, tuple] = {}
    dload_faces: dict[tuple[int, int], float] = {}  # (element, face) -> pressure
    for i, step in enumerate(scene.steps):
        for bc in step.bcs:
            old = bc_state.get(bc.on)
            if old is not None and any(o is not None and n is None for o, n in zip(old, bc.u)):
                raise NotImplementedError(f"step.{i}: group {bc.on!r} releases a component "
                                          "prescribed in an earlier step (needs *BOUNDARY, "
                                          "OP=NEW in CalculiX; not exported)")
            if len(bc.u) != 3:
                raise NotImplementedError("the CalculiX export handles 3D scenes only")
            bc_state[bc.on] = bc.u
        load_state.update({ld.on: (ld.traction, ld.pressure) for ld in step.loads})
        n_inc = step.increments
        out += [f"** step {i}: {step.name}",
                f"*STEP{', NLGEOM' if nlgeom else ''}, INC={max(100, 10 * n_inc)}",
                "*STATIC" if automatic else "*STATIC, DIRECT",
                f"{_num(1.0 / n_inc)}, 1.0" + (f", {_num(MIN_INCREMENT / n_inc)}, "
                                               f"{_num(1.0 / n_inc)}" if automatic else "")]
        if field_controls is not None:
            vals = list(field_controls)
            out += ["*CONTROLS, PARAMETERS=FIELD",
                    ", ".join("" if v is None else _num(v) for v in vals)]
        if time_controls is not None:
            out += ["*CONTROLS, PARAMETERS=TIME INCREMENTATION",
                    ", ".join("" if v is None else str(int(v)) for v in time_controls)]
        out.append("*BOUNDARY")
        for g, comps in bc_state.items():
            for c, value in enumerate(comps):
                if value is not None:
                    out.append(f"{name('N', g)}, {c + 1}, {c + 1}, {_num(value)}")
        # loads: totals, written for every node/face ever loaded so that the
        # values of this step replace (and ramp from) those of the last one
        forces = {n: np.zeros(3) for n in cload_nodes}
        pressures = dict.fromkeys(dload_faces, 0.0)
        for g, (traction, pressure) in load_state.items():
            if traction is not None:
                if len(traction) != 3:
                    raise NotImplementedError("the CalculiX export handles 3D scenes only")
                nodes, w = _traction_forces(mesh, g)
                for n, wn in zip(nodes, w):
                    forces.setdefault(int(n), np.zeros(3))
                    forces[int(n)] += wn * np.asarray(traction, float)
            if pressure is not None:
                for f in mesh.surface(g):
                    pressures[f] = pressures.get(f, 0.0) + float(pressure)
        cload_nodes, dload_faces = forces, pressures
        if cload_nodes:
            out.append("*CLOAD")
            for n, fvec in cload_nodes.items():
                out += [f"{n}, {c + 1}, {_num(fvec[c])}" for c in range(3)]
        if dload_faces:
            out.append("*DLOAD")
            out += [f"{e}, P{face}, {_num(p)}" for (e, face), p in dload_faces.items()]
        for g in reaction_groups:
            out += [f"*NODE PRINT, NSET={name('N', g)}, TOTALS=ONLY", "RF"]
        out.append("*END STEP")
    path.write_text("\n".join(out) + "\n")
    return mesh


# --------------------------------------------------------------------------- running ccx


def ccx_executable() -> Optional[str]:
    """Path of the CalculiX executable (``$CCX`` or ``ccx`` on the PATH), or None."""
    env = os.environ.get("CCX")
    if env:
        return shutil.which(env) or (env if Path(env).is_file() else None)
    return shutil.which("ccx")


def ccx_available() -> bool:
    return ccx_executable() is not None


_TOTAL = re.compile(r"^\s*total force \(fx,fy,fz\) for set (\S+) and time\s+(\S+)\s*$")


def read_dat(path: Union[str, Path], groups: Optional[dict[str, str]] = None
             ) -> tuple[dict[int, dict[int, dict[str, np.ndarray]]], dict[int, list[float]]]:
    """Reaction totals of a ``.dat`` file, ``{step: {increment: {group: (fx, fy, fz)}}}``,
    and each step's output times ``{step: [t_1, t_2, ...]}`` (total times, increment k at
    ``t_k``).

    The ``.dat`` file of a static analysis labels its blocks by the total time
    only.  Every step written by :func:`write_inp` has the time period 1, so
    total time ``t`` in ``(k, k + 1]`` belongs to step ``k`` (numbered from 0,
    as scene steps) and the increments of a step are its distinct output times
    (numbered from 1, as :class:`~dolfinx_friction.scene.driver.Increment`).
    ``groups`` maps CalculiX set names to group names (default: the set names).
    """
    groups = {k.upper(): v for k, v in (groups or {}).items()}
    result: dict[int, dict[int, dict[str, np.ndarray]]] = {}
    times: dict[int, list[float]] = {}
    lines = Path(path).read_text().splitlines()
    i = 0
    while i < len(lines):
        m = _TOTAL.match(lines[i])
        if m:
            t = float(m.group(2))
            step = max(int(math.ceil(t - 1e-9)) - 1, 0)
            seen = times.setdefault(step, [])
            if not seen or abs(t - seen[-1]) > 1e-9:
                seen.append(t)
            j = i + 1
            while j < len(lines) and not lines[j].strip():
                j += 1
            vec = np.array([float(v) for v in lines[j].split()[:3]])
            name = m.group(1).upper()
            result.setdefault(step, {}).setdefault(len(seen), {})[groups.get(name, name)] = vec
            i = j
        i += 1
    return result, times


@dataclass
class CcxRun:
    """What :func:`run_ccx` read: reactions, output times and the wall time of ``ccx``."""

    reactions: dict[int, dict[int, dict[str, np.ndarray]]]
    wall: float
    log: str
    times: dict[int, list[float]]  # each step's output times: increment k ends at times[s][k - 1]


def run_ccx(inp_path: Union[str, Path], *, threads: int = 1, timeout: float = 600.0,
            details: bool = False) -> Union[dict, CcxRun]:
    """Run ``ccx`` on a deck written by :func:`write_inp`; return its reaction sums.

    Returns ``{step: {increment: {group: np.array([fx, fy, fz])}}}`` (steps from
    0, increments from 1), or a :class:`CcxRun` with the wall time and the log
    if ``details``.  Raises :class:`CcxError` if ``ccx`` is missing, fails,
    or prints an error.
    """
    exe = ccx_executable()
    if exe is None:
        raise CcxError("CalculiX (ccx) is not installed (Debian: apt-get install calculix-ccx)")
    inp = Path(inp_path).resolve()
    if inp.suffix != ".inp":
        raise ValueError(f"{inp}: a CalculiX deck must end in .inp")
    dat = inp.with_suffix(".dat")
    if dat.exists():
        dat.unlink()
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), CCX_NPROC_STIFFNESS=str(threads),
               CCX_NPROC_EQUATION_SOLVER=str(threads), CCX_NPROC_RESULTS=str(threads))
    start = time.perf_counter()
    try:
        proc = subprocess.run([exe, "-i", inp.stem], cwd=inp.parent, env=env,
                              capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired as e:
        raise CcxError(f"ccx did not finish within {timeout:g} s") from e
    wall = time.perf_counter() - start
    log = proc.stdout + proc.stderr
    if proc.returncode != 0 or "*ERROR" in log or not dat.exists():
        tail = "\n".join([ln for ln in log.splitlines() if ln.strip()][-15:])
        raise CcxError(f"ccx failed on {inp.name} (exit status {proc.returncode}):\n{tail}")
    groups = {}
    for line in inp.read_text().splitlines():
        m = re.match(r"^\*\* dolfinx_friction reaction (\S+) (.+)$", line)
        if m:
            groups[m.group(1)] = m.group(2)
    reactions, times = read_dat(dat, groups)
    if details:
        return CcxRun(reactions, wall, log, times)
    return reactions
