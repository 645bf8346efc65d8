"""Gmsh meshes split into bodies, without dolfinx: what
:func:`~dolfinx_friction.io.gmsh.load_mesh` and the CalculiX deck writer
(:mod:`dolfinx_friction.reference.calculix`) both read.

A *body* is a named physical group of cells (dimension 3 in 3D, 2 in 2D).  Each body
gets its own copy of its nodes, so two bodies never share nodes even when the Gmsh mesh
is conforming (fragmented).  Every other named physical group (facets, edges, points, or
cell subregions) is given to each body that contains all of its nodes, as body-local
node indices (:class:`MeshSplit`).

Files: only a regular file that starts as Gmsh MSH 2.2 or 4.1 and declares no more nodes
and elements than it can hold is given to gmsh (its MSH reader, never its script
interpreter), through a link in a private directory (gmsh would merge a ``.opt`` script
beside the mesh).  A file read once is read again from :mod:`~dolfinx_friction.io.mesh_cache`.
"""
from __future__ import annotations

import contextlib
import hashlib
import mmap
import os
import re
import stat
import tempfile
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional, Sequence, Union

import numpy as np

from dolfinx_friction.io import mesh_cache
from dolfinx_friction.io.files import file_fault

__all__ = ["MeshError", "MeshSplit", "SplitBody", "SplitGroup", "read_split", "split",
           "group_elements", "corner_jacobians", "check_msh", "gmsh_initialized", "GMSH_NAMES"]


class MeshError(ValueError):
    """A mesh that cannot be used; the message names the file / group at fault."""


# Gmsh element type -> (dolfinx cell name, number of nodes) for the cells a
# body may be made of.
_BODY_TYPES: dict[int, tuple[str, int]] = {
    2: ("triangle", 3), 9: ("triangle", 6),
    3: ("quadrilateral", 4), 10: ("quadrilateral", 9),
    4: ("tetrahedron", 4), 11: ("tetrahedron", 10),
    5: ("hexahedron", 8), 12: ("hexahedron", 27),
}
# Gmsh element type -> (dolfinx cell name, number of nodes) for any entity.
_ENTITY_TYPES: dict[int, tuple[str, int]] = {
    15: ("point", 1), 1: ("interval", 2), 8: ("interval", 3), **_BODY_TYPES,
}
# Body cell type -> {entity dim: Gmsh element type of its entities of that dim}.
_SUB_TYPES: dict[int, dict[int, int]] = {
    2: {0: 15, 1: 1}, 9: {0: 15, 1: 8},
    3: {0: 15, 1: 1}, 10: {0: 15, 1: 8},
    4: {0: 15, 1: 1, 2: 2}, 11: {0: 15, 1: 8, 2: 9},
    5: {0: 15, 1: 1, 2: 3}, 12: {0: 15, 1: 8, 2: 10},
}
#: Gmsh element type -> its name (as gmsh says it)
GMSH_NAMES = {15: "Point", 1: "Line 2", 8: "Line 3", 2: "Triangle 3", 9: "Triangle 6",
              3: "Quadrilateral 4", 10: "Quadrilateral 9", 16: "Quadrilateral 8",
              4: "Tetrahedron 4", 11: "Tetrahedron 10", 5: "Hexahedron 8",
              12: "Hexahedron 27", 17: "Hexahedron 20", 6: "Prism 6", 7: "Pyramid 5"}


# --------------------------------------------------------------------------
# The split, from the current Gmsh model
# --------------------------------------------------------------------------
@dataclass
class SplitGroup:
    """The elements of one Gmsh type of a named group on one body."""

    name: str
    dim: int
    gmsh_type: int
    count: int                     # number of distinct elements
    entities: Optional[np.ndarray]  # (count, nodes) body-local node indices, gmsh order (rank 0)


@dataclass
class SplitBody:
    """One body: its cells on its own nodes, and the groups that lie on it."""

    name: str
    gmsh_type: int
    num_cells: int
    cells: Optional[np.ndarray]  # (num_cells, nodes) body-local node indices, gmsh order (rank 0)
    x: Optional[np.ndarray]      # (num_nodes, gdim) (rank 0)
    groups: list[SplitGroup] = field(default_factory=list)

    def strip(self) -> "SplitBody":
        """Copy without the arrays (what the other ranks get)."""
        return SplitBody(self.name, self.gmsh_type, self.num_cells, None, None,
                         [SplitGroup(g.name, g.dim, g.gmsh_type, g.count, None)
                          for g in self.groups])


@dataclass
class MeshSplit:
    """All bodies of a mesh; ``group_dims``, ``group_bodies`` and ``group_touches`` as in
    :class:`~dolfinx_friction.io.gmsh.MeshSet`."""

    gdim: int
    bodies: list[SplitBody]
    group_dims: dict[str, int]
    group_bodies: dict[str, tuple[str, ...]]
    group_touches: dict[str, tuple[str, ...]] = field(default_factory=dict)


def _type_name(gmsh, etype: int) -> str:
    try:
        return str(gmsh.model.mesh.getElementProperties(etype)[0])
    except Exception:  # pragma: no cover - unknown to gmsh itself
        return GMSH_NAMES.get(etype, f"type {etype}")


def _unique_rows(a: np.ndarray) -> np.ndarray:
    """Drop repeated elements (same node set), keeping the first occurrence."""
    if len(a) < 2:
        return a
    _, first = np.unique(np.sort(a, axis=1), axis=0, return_index=True)
    return a[np.sort(first)]


def group_elements(gmsh, dim: int, tags: Sequence[int]) -> dict[int, np.ndarray]:
    """Element type -> (n, nodes per element) Gmsh node tags of a physical group."""
    blocks: dict[int, list[np.ndarray]] = {}
    for tag in tags:
        for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
            types, _, nodes = gmsh.model.mesh.getElements(dim, int(ent))
            for etype, enodes in zip(types, nodes):
                nn = int(gmsh.model.mesh.getElementProperties(int(etype))[3])
                blocks.setdefault(int(etype), []).append(
                    np.asarray(enodes, dtype=np.int64).reshape(-1, nn))
    return {t: _unique_rows(np.concatenate(b)) for t, b in blocks.items()}


def split(gmsh, body_names: Sequence[str], where: str) -> MeshSplit:
    """The bodies of the current Gmsh model; raises :class:`MeshError` (``where`` names
    the file or model in the messages)."""
    # Named physical groups: name -> (dim, [tags])
    named: dict[str, tuple[int, list[int]]] = {}
    all_dims = []
    for dim, tag in gmsh.model.getPhysicalGroups():
        all_dims.append(dim)
        name = gmsh.model.getPhysicalName(dim, tag)
        if not name:
            continue
        if name in named and named[name][0] != dim:
            raise MeshError(f"{where}: physical group name '{name}' is used for dimensions "
                            f"{named[name][0]} and {dim}")
        named.setdefault(name, (dim, []))[1].append(tag)
    if not named:
        raise MeshError(f"{where}: no named physical groups")
    available = ", ".join(sorted(named))

    if len(set(body_names)) != len(body_names):
        raise MeshError(f"{where}: body names {list(body_names)} contain duplicates")
    if not body_names:
        raise MeshError(f"{where}: no body names given (available groups: {available})")
    for b in body_names:
        if b not in named:
            raise MeshError(f"{where}: body '{b}' is not a physical group "
                            f"(available: {available})")
    tdim = max(all_dims)
    for b in body_names:
        d = named[b][0]
        if d != tdim or d not in (2, 3):
            expected = tdim if tdim in (2, 3) else "2 or 3"
            raise MeshError(f"{where}: body group '{b}' has dimension {d}, expected {expected} "
                            "(bodies are groups of cells)")
    gdim = tdim

    # Elements of every named group
    elements: dict[str, dict[int, np.ndarray]] = {}
    for name, (dim, tags) in named.items():
        elems = group_elements(gmsh, dim, tags)
        if sum(len(a) for a in elems.values()) == 0:
            raise MeshError(f"{where}: physical group '{name}' is empty (no mesh elements)")
        elements[name] = elems

    # Nodes
    node_tags, coords, _ = gmsh.model.mesh.getNodes()
    node_tags = np.asarray(node_tags, dtype=np.int64)
    coords = np.asarray(coords, dtype=np.float64).reshape(-1, 3)
    node_tags, first = np.unique(node_tags, return_index=True)
    coords = coords[first]
    if gdim == 2 and len(coords):
        z = coords[:, 2]
        scale = max(1.0, float(np.ptp(coords[:, :2], axis=0).max()))
        if np.ptp(z) > 1e-10 * scale:
            raise MeshError(f"{where}: 2D bodies but the node z coordinates are not constant "
                            f"(from {z.min():g} to {z.max():g})")

    def node_rows(tags: np.ndarray, what: str) -> np.ndarray:
        pos = np.searchsorted(node_tags, tags)
        pos = np.minimum(pos, len(node_tags) - 1)
        if len(node_tags) == 0 or np.any(node_tags[pos] != tags):
            raise MeshError(f"{where}: {what} refers to nodes that do not exist")
        return pos

    # Bodies
    bodies: list[SplitBody] = []
    body_nodes: dict[str, np.ndarray] = {}
    for b in body_names:
        elems = elements[b]
        if len(elems) > 1:
            kinds = ", ".join(_type_name(gmsh, t) for t in sorted(elems))
            raise MeshError(f"{where}: body '{b}' has mixed cell types ({kinds})")
        (etype, cells), = elems.items()
        if etype not in _BODY_TYPES:
            extra = (" (incomplete second order: mesh with Mesh.SecondOrderIncomplete = 0)"
                     if etype in (16, 17) else "")
            raise MeshError(f"{where}: body '{b}' has unsupported element type "
                            f"'{_type_name(gmsh, etype)}'{extra}; supported: triangle, "
                            "quadrilateral, tetrahedron, hexahedron of order 1 or 2")
        nodes = np.unique(cells)
        rows = node_rows(nodes, f"body '{b}'")
        body_nodes[b] = nodes
        plan = SplitBody(b, etype, len(cells), np.searchsorted(nodes, cells),
                         coords[rows, :gdim].copy())
        _check_cells(plan, nodes, where)
        bodies.append(plan)

    # Other groups: give each to every body containing all of its nodes
    group_bodies: dict[str, tuple[str, ...]] = {}
    group_touches: dict[str, tuple[str, ...]] = {}
    for name, (dim, _) in named.items():
        if name in body_names:
            group_bodies[name] = group_touches[name] = (name,)
            continue
        elems = elements[name]
        gnodes = np.unique(np.concatenate([a.ravel() for a in elems.values()]))
        owners, touched = [], []
        for bp in bodies:
            nodes = body_nodes[bp.name]
            inside = np.isin(gnodes, nodes, assume_unique=True)
            if np.any(inside):
                touched.append(bp.name)
            if not np.all(inside):
                continue
            expected = bp.gmsh_type if dim == tdim else _SUB_TYPES[bp.gmsh_type][dim]
            for etype, ents in elems.items():
                if etype != expected:
                    raise MeshError(
                        f"{where}: group '{name}' has '{_type_name(gmsh, etype)}' elements, "
                        "but the "
                        f"{dim}-dimensional entities of body '{bp.name}' are "
                        f"'{_type_name(gmsh, expected)}'")
                bp.groups.append(SplitGroup(name, dim, etype, len(ents),
                                            np.searchsorted(nodes, ents)))
            owners.append(bp.name)
        group_bodies[name] = tuple(owners)
        group_touches[name] = tuple(touched)

    return MeshSplit(gdim, bodies, {n: d for n, (d, _) in named.items()}, group_bodies,
                 group_touches)


# Corner -> its neighbours along the reference axes (Gmsh node order), so that the
# corner's Jacobian determinant is positive for a positively oriented cell.
_CORNERS: dict[str, tuple[tuple[int, ...], ...]] = {
    "triangle": ((0, 1, 2),),
    "tetrahedron": ((0, 1, 2, 3),),
    "quadrilateral": ((0, 1, 3), (1, 2, 0), (2, 3, 1), (3, 0, 2)),
    "hexahedron": ((0, 1, 3, 4), (1, 2, 0, 5), (2, 3, 1, 6), (3, 0, 2, 7),
                   (4, 7, 5, 0), (5, 4, 6, 1), (6, 5, 7, 2), (7, 6, 4, 3)),
}


def corner_jacobians(cells: np.ndarray, x: np.ndarray, shape: str) -> np.ndarray:
    """(n_cells, n_corners) Jacobian determinants of the straight-sided cells at their corners."""
    dets = []
    for corner, *axes in _CORNERS[shape]:
        edges = np.stack([x[cells[:, a]] - x[cells[:, corner]] for a in axes], axis=-1)
        dets.append(np.linalg.det(edges))
    return np.stack(dets, axis=1)


def _check_cells(plan: SplitBody, node_tags: np.ndarray, where: str) -> None:
    """Refuse non-finite node coordinates and cells of zero or negative measure.

    A cell is degenerate when a corner Jacobian is zero (relative to its size) or of
    the other sign than at its other corners (a tangled cell).  Cells numbered the
    other way round (all corners negative) are fine.
    """
    x, cells = plan.x, plan.cells
    bad = ~np.all(np.isfinite(x), axis=1)
    if np.any(bad):
        raise MeshError(f"{where}: body '{plan.name}' has non-finite node coordinates "
                        f"(node {int(node_tags[np.argmax(bad)])}: {x[np.argmax(bad)].tolist()})")
    shape = _BODY_TYPES[plan.gmsh_type][0]
    with np.errstate(all="ignore"):
        dets = corner_jacobians(cells, x, shape)
        size = np.ptp(x[cells], axis=1).max(axis=1) ** x.shape[1]
        sign = np.where(dets.sum(axis=1) < 0, -1.0, 1.0)[:, None]
        bad = np.any(sign * dets <= 1e-12 * size[:, None], axis=1)
    if np.any(bad):
        cell = int(np.argmax(bad))
        raise MeshError(f"{where}: body '{plan.name}' has {int(np.sum(bad))} cell(s) of zero "
                        f"or negative measure (the first: cell {cell} of the body, nodes "
                        f"{node_tags[cells[cell]].tolist()})")


def gmsh_initialized(gmsh) -> bool:
    f = getattr(gmsh, "isInitialized", None)  # gmsh >= 4.9
    if f is not None:
        return bool(f())
    try:  # gmsh 4.8: options read as empty before initialize(), raise after finalize()
        return gmsh.option.getString("General.Version") != ""
    except Exception:
        return False


# The first line of a Gmsh MSH file and its format line: "version file-type data-size".
_MSH_FORMAT = re.compile(rb"\$MeshFormat\r?\n(2\.2|4\.1) ([01]) (\d+)\r?\n")
# Section -> (position of the declared count on its first line, at least how many
# bytes each item takes in the file) for MSH 2.2 and 4.1.
_MSH_COUNTS = {"2.2": {b"$Nodes": (0, 8), b"$Elements": (0, 4)},
               "4.1": {b"$Nodes": (1, 8), b"$Elements": (1, 4)}}


def _declared_counts(data: Any, version: str, binary: int, where: str) -> None:
    """Refuse a node or element count that the file is far too small to hold."""
    size = len(data)
    for section, (position, item_bytes) in _MSH_COUNTS[version].items():
        at = data.find(b"\n" + section + b"\n")
        if at < 0:
            continue
        start = at + len(section) + 2
        if binary and version == "4.1":  # four size_t values (binary = sizeof(size_t))
            if binary not in (4, 8) or start + 4 * binary > size:
                continue
            words = np.frombuffer(data[start:start + 4 * binary], dtype=f"<u{binary}")
            count = int(words[position])
        else:
            line = bytes(data[start:start + 200]).split(b"\n", 1)[0].split()
            if len(line) <= position or not line[position].isdigit():
                raise MeshError(f"{where} cannot be read: its {section.decode()} section "
                                "does not start with its count")
            count = int(line[position])
        if count * item_bytes > size:
            raise MeshError(f"{where} declares {count} {section.decode()[1:].lower()}, "
                            f"more than its {size} bytes can hold")


def check_msh(path: Path, fd: int) -> None:
    """Raise MeshError unless the open file ``fd`` is Gmsh MSH 2.2 or 4.1 (ASCII or binary).

    Only the header and the declared node and element counts are read: a file that
    passes is given to gmsh's MSH reader, never to its script (.geo) interpreter.
    """
    where = f"mesh file '{path}'"
    head = os.pread(fd, 64, 0)
    match = _MSH_FORMAT.match(head)
    if match is None:
        found = head.split(b"\n", 1)[0][:40].decode("ascii", "replace")
        raise MeshError(f"{where} cannot be read: it is not Gmsh MSH 2.2 or 4.1 (that "
                        "starts with '$MeshFormat' and a line 'version file-type data-size'; "
                        f"it starts with {found!r})")
    version = match.group(1).decode()
    binary = int(match.group(3)) if match.group(2) == b"1" else 0
    if os.fstat(fd).st_size == 0:  # pragma: no cover - the header was read
        return
    with mmap.mmap(fd, 0, access=mmap.ACCESS_READ) as data:
        _declared_counts(data, version, binary, where)


@contextlib.contextmanager
def _checked_file(path: Path):
    """The descriptor of ``path``, opened and checked as MSH, for the ``with`` block."""
    where = f"mesh file '{path}'"
    fault = file_fault(path)
    if fault == "no such file":
        raise MeshError(f"{where} does not exist")
    if fault is not None:
        raise MeshError(f"{where}: {fault}")
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as e:
        raise MeshError(f"{where} cannot be opened: {e.strerror}") from None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise MeshError(f"{where}: is not a regular file")
        check_msh(path, fd)
        yield fd
    finally:
        os.close(fd)


@contextlib.contextmanager
def _private_link(fd: int):
    """The checked file ``fd`` seen through a link in a private directory.

    gmsh merges ``<file>.opt`` (a script) when it finds one next to a mesh, and it
    chooses its reader from the name: the link is named ``mesh.msh`` in a fresh
    directory, and points at the very file that was checked (``/proc/self/fd``).
    """
    with tempfile.TemporaryDirectory(prefix="dolfinx_friction_mesh_") as tmp:
        link = Path(tmp) / "mesh.msh"
        os.symlink(f"/proc/self/fd/{fd}", link)
        yield link


@contextlib.contextmanager
def _merged(path: Path, fd: int):
    """gmsh with the checked file ``fd`` (opened from ``path``) merged into a fresh model."""
    import gmsh

    where = f"mesh file '{path}'"
    with _private_link(fd) as link:
        own = not gmsh_initialized(gmsh)
        if own:
            gmsh.initialize()
            previous, terminal = None, None
        else:
            previous = gmsh.model.getCurrent()
            terminal = gmsh.option.getNumber("General.Terminal")
        gmsh.option.setNumber("General.Terminal", 0)
        name = f"dolfinx_friction_{uuid.uuid4().hex}"
        try:
            gmsh.model.add(name)
            try:
                gmsh.merge(str(link))
            except Exception as e:
                message = str(e).replace(str(link), str(path))
                raise MeshError(f"{where} cannot be read: {message}") from None
            yield gmsh
        finally:
            try:
                gmsh.model.setCurrent(name)
                gmsh.model.remove()
            except Exception:  # pragma: no cover
                pass
            if own:
                gmsh.finalize()
            else:
                gmsh.option.setNumber("General.Terminal", terminal)
                if previous is not None and previous in gmsh.model.list():
                    gmsh.model.setCurrent(previous)


def _read_file(path: Path, body_names: Sequence[str]) -> MeshSplit:
    """The split of a mesh file: from :mod:`mesh_cache` if it was read before, else with
    gmsh (and then cached)."""
    with _checked_file(path) as fd:
        name = mesh_cache.key(fd, body_names, _reader_identity())
        entry = mesh_cache.load(name) if name else None
        if entry is not None:
            return _plan_from_record(*entry)
        with _merged(path, fd) as gmsh:
            plan = split(gmsh, body_names, f"mesh file '{path}'")
    if name:
        mesh_cache.store(name, *_plan_record(plan))
    return plan


def _reader_identity() -> str:
    """The SHA-256 of this module's source: cached splits are what its reader made."""
    return hashlib.sha256(Path(__file__).read_bytes()).hexdigest()


def _plan_record(plan: MeshSplit) -> tuple[dict, dict[str, np.ndarray]]:
    """A split as a JSON-able header and named arrays (:mod:`mesh_cache`)."""
    arrays = {}
    bodies = []
    for i, b in enumerate(plan.bodies):
        arrays[f"b{i}_cells"], arrays[f"b{i}_x"] = b.cells, b.x
        for j, g in enumerate(b.groups):
            arrays[f"b{i}_g{j}"] = g.entities
        bodies.append({"name": b.name, "gmsh_type": int(b.gmsh_type),
                       "num_cells": int(b.num_cells),
                       "groups": [[g.name, int(g.dim), int(g.gmsh_type), int(g.count)]
                                  for g in b.groups]})
    header = {"gdim": int(plan.gdim), "bodies": bodies,
              "group_dims": {k: int(v) for k, v in plan.group_dims.items()},
              "group_bodies": plan.group_bodies, "group_touches": plan.group_touches}
    return header, arrays


def _plan_from_record(header: dict, arrays: dict[str, np.ndarray]) -> MeshSplit:
    """The inverse of :func:`_plan_record`."""
    bodies = []
    for i, b in enumerate(header["bodies"]):
        groups = [SplitGroup(name, dim, gtype, count, arrays[f"b{i}_g{j}"])
                  for j, (name, dim, gtype, count) in enumerate(b["groups"])]
        bodies.append(SplitBody(b["name"], b["gmsh_type"], b["num_cells"], arrays[f"b{i}_cells"],
                                arrays[f"b{i}_x"], groups))
    return MeshSplit(header["gdim"], bodies, dict(header["group_dims"]),
                 {k: tuple(v) for k, v in header["group_bodies"].items()},
                 {k: tuple(v) for k, v in header["group_touches"].items()})


def _read_live(gmsh, body_names: Sequence[str]) -> MeshSplit:
    if not gmsh_initialized(gmsh):
        raise MeshError("live gmsh model: gmsh is not initialized")
    where = f"gmsh model '{gmsh.model.getCurrent()}'"
    return split(gmsh, body_names, where)


def read_split(source: Union[str, Path, Any], body_names: Sequence[str]) -> MeshSplit:
    """The bodies of a Gmsh mesh: ``source`` a ``.msh`` file (format 2.2 or 4.1) or the
    ``gmsh`` module with a live, meshed model (its current model, left as it is).

    In this process only (no MPI).  Raises :class:`MeshError` for a missing, unreadable or
    unsafe file, no named groups, an unknown body name, a body group of the wrong
    dimension, an empty group, mixed or unsupported cell types, non-planar 2D meshes,
    non-finite coordinates or cells of zero or negative measure.
    """
    if isinstance(source, (str, os.PathLike)):
        return _read_file(Path(source), body_names)
    return _read_live(source, body_names)
