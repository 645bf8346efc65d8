"""The rules of a valid scene, shared by the Python API and the scene-file reader.

No dolfinx here.  Every :mod:`dolfinx_friction.scene.model` dataclass checks its fields on
construction with the rules of its scene-file table (types, ranges, finite numbers,
allowed strings, and the checks across fields); :class:`~dolfinx_friction.scene.model.Scene`
checks the whole (unique names, references between sections, one vector length).  The
scene reader (:mod:`dolfinx_friction.scene.toml`) builds the same dataclasses, so a scene
file and a script are held to one set of rules with one set of messages.

:func:`check_mesh_file` tells whether the mesh file can be read at all (the command line
and ``sweep``, before dolfinx is imported).  What needs the mesh is checked when the scene
is put on it (:class:`~dolfinx_friction.scene.build.DiscreteScene`, for ``run`` and
``check`` alike), by :func:`check_groups`, :func:`check_solvable`, :func:`check_held` and
:func:`check_bcs`; they raise :class:`ModelError`, naming the key as above.

Every problem raises :class:`SceneError` with one line naming the field by its scene-file key
path.  A scene file's path has the array indices (``contact.0.mu``); an object built in Python
is named by its table without an index (``contact.mu`` for a ``ContactPair``, ``step.bc.u``
for a ``BC``), while the checks of a whole ``Scene`` index its tuples (``contact.1.slave`` is
``scene.contacts[1].slave``)::

    scene.toml: contact.0.mu = -0.1: must be >= 0
    contact.mu = -0.1: must be >= 0
"""
from __future__ import annotations

import os
from collections import Counter
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any, Optional, Union

from dolfinx_friction.fem.contact_settings import (  # noqa: F401  (re-exported)
    _LAW_REQUIRES, check_law, pressure_table)
from dolfinx_friction.fem.obstacles import (  # noqa: F401  (re-exported)
    _GEOMETRY_KEYS, SHAPE_KEYS, check_shape)
from dolfinx_friction.rules import (  # noqa: F401  (the engine, re-exported)
    ANY_NUMBER, CALCULIX, PRESSURE, Check, Key, Rules, SceneError, _is_list, _is_number,
    _toml, array_name, boolean, exactly_one, fail, integer, join, modulus, name, number,
    one_of, penalty, place, rotation, show, string, suggest, validate, vector)
from dolfinx_friction.rules import _list_of_2_or_3  # noqa: F401
from dolfinx_friction.io.files import file_fault
from dolfinx_friction.nls.defaults import unsafe_option


class ModelError(ValueError):
    """The scene does not fit its mesh (a missing group, a group of the wrong kind...), or
    cannot be solved as given (a body nothing holds, conflicting bcs, a modulus too large)."""


def names(value: Any, key: str) -> tuple[str, ...]:
    """A list of distinct group names."""
    if not _is_list(value):
        fail(key, "must be a list of group names", value)
    listed = tuple(name(v, join(key, i)) for i, v in enumerate(value))
    for i, item in enumerate(listed):
        if item in listed[:i]:
            fail(join(key, i), "listed twice", item)
    return listed


def msh_file(value: Any, key: str) -> str:
    """The name of a Gmsh ``.msh`` file."""
    if not name(value, key).lower().endswith(".msh"):
        fail(key, "must be a Gmsh .msh file", value)
    return value


def directory(value: Any, key: str) -> Path:
    """A directory: a non-empty string or a path."""
    return Path(value if isinstance(value, os.PathLike) else name(value, key))


def mesh_source(value: Any, key: str) -> Any:
    """A mesh file (a str or path; the mesh loader reads it as Gmsh MSH 2.2 or 4.1 or refuses
    it), or a live gmsh model (the ``gmsh`` module)."""
    return Path(value) if isinstance(value, (str, os.PathLike)) else value


def _component(value: Any, key: str) -> Optional[float]:
    """A prescribed displacement component; ``"free"`` (in Python also ``None``): free."""
    if value is None or value == "free":
        return None
    if not _is_number(value):
        fail(key, 'must be a number or "free"', value)
    return ANY_NUMBER(value, key)


def displacement(value: Any, key: str) -> tuple[Optional[float], ...]:
    items = _list_of_2_or_3(value, key, 'components (numbers or "free")')
    return tuple(_component(v, join(key, i)) for i, v in enumerate(items))


def items(cls: type, min_length: int = 0) -> Check:
    """A sequence of ``cls`` objects (a table's array in Python), as a tuple."""

    def check(value: Any, key: str) -> tuple:
        if not _is_list(value) or not all(isinstance(v, cls) for v in value):
            fail(key, f"must be a sequence of {cls.__name__}")
        if len(value) < min_length:
            fail(key, f"needs at least {min_length} {cls.__name__}")
        return tuple(value)

    return check


def petsc_options(value: Any, key: str) -> tuple[tuple[str, Any], ...]:
    """PETSc options without their dash (``{ksp_type = "cg", ksp_rtol = 1e-8}``): names of
    letters, digits and underscores; values strings, numbers or booleans; none that would
    run code or write a file (:func:`~dolfinx_friction.nls.defaults.unsafe_option`).
    Kept as sorted ``(name, value)`` pairs (which it takes as well)."""
    if isinstance(value, (tuple, list)) and all(isinstance(p, tuple) and len(p) == 2
                                                for p in value):
        value = dict(value)
    if not isinstance(value, Mapping):
        fail(key, "must be a table of PETSc options (name = value)", value)
    for option, setting in value.items():
        at = join(key, option)
        if not (isinstance(option, str) and option.replace("_", "").isalnum()
                and option[:1].isalpha()):
            fail(at, "must be a PETSc option name without its dash (letters, digits, _)")
        if isinstance(setting, float):
            number()(setting, at)
        elif not isinstance(setting, (str, int, bool)):
            fail(at, "must be a string, a number or true/false", setting)
        why = unsafe_option(option, setting)
        if why:
            fail(at, f"is not allowed: it {why}", setting)
    return tuple(sorted(value.items()))


def instance(cls: type) -> Check:
    def check(value: Any, key: str) -> Any:
        if not isinstance(value, cls):
            fail(key, f"must be of type {cls.__name__}")
        return value

    return check



def check_not_self_contact(pair: Any, key: str) -> None:
    if pair.slave == pair.master:
        fail(join(key, "master"), "must differ from the slave", pair.master)


def _check_once_per_step(entries: Sequence[Any], key: str, attr: str) -> None:
    """Within one step a group (or obstacle) is named by at most one entry of a kind."""
    first: dict[str, int] = {}
    for j, item in enumerate(entries):
        name_ = getattr(item, attr)
        if name_ in first:
            fail(join(join(key, j), attr), f"already given in this step by "
                 f"{join(key, first[name_])}", name_)
        first[name_] = j


def check_body(body: Any, key: str) -> None:
    if body.plane == "axisymmetric" and body.thickness != 1.0:
        fail(join(key, "thickness"), "does not apply to an axisymmetric body (its values "
             "are per full revolution)", body.thickness)


def check_step(step: Any, key: str) -> None:
    _check_once_per_step(step.bcs, join(key, "bc"), "on")
    _check_once_per_step(step.loads, join(key, "load"), "on")
    _check_once_per_step(step.rigid, join(key, "rigid"), "name")


# ---- the whole scene


def _check_unique_names(entries: Sequence[Any], key: str) -> None:
    first: dict[str, int] = {}
    for i, item in enumerate(entries):
        if item.name in first:
            fail(join(join(key, i), "name"), f"duplicate name (also {key}.{first[item.name]})",
                 item.name)
        first[item.name] = i


def _check_contacts(scene: Any) -> None:
    rigids = {r.name for r in scene.rigids}
    seen: dict[tuple[str, str], int] = {}
    for i, pair in enumerate(scene.contacts):
        if pair.slave in rigids:
            fail(f"contact.{i}.slave", "names a [[rigid]] obstacle; a slave must be a facet group",
                 pair.slave)
        first = seen.setdefault((pair.slave, pair.master), i)
        if first != i:
            fail(f"contact.{i}", f"same slave and master as contact.{first}")


def _check_models(scene: Any) -> None:
    for i, body in enumerate(scene.bodies):
        if body.finite_strain and body.plane == "stress":
            fail(f"body.{i}.plane", f"plane stress is not available at finite strain (model "
                 f"{body.model!r}): use plane strain or a 3D mesh", body.plane)


def _check_rigid_motions(scene: Any) -> None:
    rigids = [r.name for r in scene.rigids]
    for i, step in enumerate(scene.steps):
        for j, motion in enumerate(step.rigid):
            if motion.name not in rigids:
                fail(f"step.{i}.rigid.{j}.name", "no [[rigid]] of that name"
                     + suggest(motion.name, rigids), motion.name)
            if (motion.rotation is not None and any(motion.rotation)
                    and any(b.axisymmetric for b in scene.bodies)):
                fail(f"step.{i}.rigid.{j}.rotation", "an obstacle of an axisymmetric scene "
                     "cannot turn (a turn in the meridian section is no axisymmetric motion)",
                     list(motion.rotation))


def _vectors(scene: Any) -> Iterator[tuple[str, tuple]]:
    """Every vector of the scene with its key path."""
    for i, rigid in enumerate(scene.rigids):
        for name_ in ("point", "normal", "center", "axis", "reference"):
            if getattr(rigid, name_) is not None:
                yield f"rigid.{i}.{name_}", getattr(rigid, name_)
    for i, step in enumerate(scene.steps):
        for j, bc in enumerate(step.bcs):
            yield f"step.{i}.bc.{j}.u", bc.u
        for j, load in enumerate(step.loads):
            if load.traction is not None:
                yield f"step.{i}.load.{j}.traction", load.traction
        for j, motion in enumerate(step.rigid):
            for name_ in ("displacement", "force"):
                if getattr(motion, name_) is not None:
                    yield f"step.{i}.rigid.{j}.{name_}", getattr(motion, name_)


def _check_dimension(scene: Any) -> None:
    """All vectors have one length, the (yet unknown) mesh dimension; cylinders are 3D.

    The dimension is the most common length (the first one on a tie), so the
    message blames the odd vector out.
    """
    vectors = list(_vectors(scene))
    if not vectors:
        return
    lengths = Counter(len(v) for _, v in vectors)
    dim = lengths.most_common(1)[0][0]
    example = next(key for key, v in vectors if len(v) == dim)
    for key, v in vectors:
        if len(v) != dim:
            fail(key, f"has {len(v)} components but {example} has {dim} "
                 "(every vector has the mesh dimension)")
    if dim == 2:
        for i, rigid in enumerate(scene.rigids):
            if rigid.shape == "cylinder":
                fail(f"rigid.{i}.shape", f"is 3D only, but {example} has 2 components",
                     rigid.shape)
    for i, step in enumerate(scene.steps):
        for j, motion in enumerate(step.rigid):
            if motion.rotation is not None and len(motion.rotation) != (1 if dim == 2 else 3):
                what = ("an angle (a number) in 2D" if dim == 2
                        else "a rotation vector of 3 numbers in 3D")
                fail(f"step.{i}.rigid.{j}.rotation", f"must be {what} ({example} has {dim} "
                     "components)", list(motion.rotation))


def check_scene(scene: Any, key: str) -> None:
    """The checks across sections (their key paths index the scene's tuples)."""
    _check_unique_names(scene.bodies, "body")
    _check_unique_names(scene.rigids, "rigid")
    _check_unique_names(scene.steps, "step")
    _check_contacts(scene)
    _check_models(scene)
    _check_rigid_motions(scene)
    _check_dimension(scene)


# --------------------------------------------------------------------------- on the mesh
#
# ``meshes`` is a :class:`~dolfinx_friction.io.gmsh.MeshSet` (``gdim``, ``group_dims``,
# ``group_bodies``, ``group_touches``, ``bodies[name].interior_facets(group)``), ``fields``
# the bodies' :class:`~dolfinx_friction.fem.numbering.BodyField` (``body``, ``n_owned``,
# ``owned_group_nodes(group)``): used here by their attributes only.

def check_mesh_file(scene: Any, source: Union[str, Path, None] = None) -> None:
    """The scene's mesh file is there and is a regular file (what can be told before the
    mesh is read); ``source`` names the scene file in the message."""
    if not isinstance(scene.mesh, (str, os.PathLike)):
        return  # a live gmsh model
    reason = file_fault(scene.mesh)
    if reason is not None:
        raise SceneError(f"mesh.file: {scene.mesh}: {reason}", key="mesh.file",
                         source=None if source is None else str(source))


#: Largest Young's modulus, penalty K or stick slope a scene may give: forces of order
#: E L^2 are squared in residual norms (sqrt of the largest double: 1.3e154); 1e150 leaves
#: room for the areas, displacements and dof counts, and is far beyond any material in any
#: unit system (diamond: 1.2e12 Pa).
MAX_MODULUS = 1e150


def check_groups(scene: Any, meshes: Any) -> None:
    """Every group the scene names exists in the mesh, is of the right kind and lies where
    it must; every vector has the mesh's dimension."""
    dims, fdim, gdim = meshes.group_dims, meshes.gdim - 1, meshes.gdim
    for i, r in enumerate(scene.rigids):
        if r.name in dims:
            raise ModelError(f"rigid.{i}.name: {r.name!r} is also a physical group of the "
                             "mesh: ambiguous as a contact master (rename the obstacle)")
    for k, c in enumerate(scene.contacts):
        if c.slave not in dims:
            raise ModelError(f"contact.{k}.slave: no physical group {c.slave!r} in the mesh")
        if dims[c.slave] != fdim:
            raise ModelError(f"contact.{k}.slave: group {c.slave!r} has dimension "
                             f"{dims[c.slave]}, contact surfaces need {fdim}")
        if scene.rigid(c.master) is None:
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
            owners = meshes.group_bodies.get(g, ())
            if len(owners) != 1:
                touched = meshes.group_touches.get(g, ())
                raise ModelError(
                    f"contact.{k}.{role}: group {g!r} " + (
                        f"lies on {len(owners)} bodies at once ({', '.join(owners)}: "
                        "their meshes share its nodes)" if owners else
                        f"spans the bodies {', '.join(touched)}" if len(touched) > 1 else
                        "lies on none of the bodies") +
                    "; a contact surface must lie on exactly one body")
            inside = meshes.bodies[owners[0]].interior_facets(g)
            if inside:
                raise ModelError(f"contact.{k}.{role}: group {g!r} has {inside} facet(s) "
                                 f"inside body {owners[0]!r}; a contact surface must be on "
                                 "the body's boundary")
    for i, step in enumerate(scene.steps):
        for j, bc in enumerate(step.bcs):
            _check_node_group(meshes, bc.on, f"step.{i}.bc.{j}.on")
        for j, load in enumerate(step.loads):
            _check_node_group(meshes, load.on, f"step.{i}.load.{j}.on")
            if dims[load.on] != fdim:
                raise ModelError(f"step.{i}.load.{j}.on: group {load.on!r} is not a facet "
                                 f"group")
    for g in scene.output.reactions or ():
        _check_node_group(meshes, g, "output.reactions")
    # (the steps' vectors first, as a scene file lists them)
    wrong = sorted(((key, v) for key, v in _vectors(scene) if len(v) != gdim),
                   key=lambda item: not item[0].startswith("step."))
    if wrong:
        key, v = wrong[0]
        raise ModelError(f"{key} has {len(v)} components, but the mesh {scene.mesh} is "
                         f"{gdim}D (every vector has the mesh dimension)")
    for i, b in enumerate(scene.bodies):
        if gdim == 3 and b.axisymmetric:
            raise ModelError(f"body.{i}.plane = \"axisymmetric\": body {b.name!r} needs a "
                             f"2D mesh (a meridian section), the mesh {scene.mesh} is 3D")
        if gdim == 3 and (b.plane != "strain" or b.thickness != 1.0):
            raise ModelError(f"body {b.name!r}: plane/thickness apply to 2D meshes only")


def _check_node_group(meshes: Any, group: str, key: str) -> None:
    if group not in meshes.group_dims:
        raise ModelError(f"{key}: no physical group {group!r} in the mesh")
    if not meshes.group_bodies.get(group):
        raise ModelError(f"{key}: group {group!r} lies on no deformable body")


def check_solvable(scene: Any) -> None:
    """Refuse moduli and penalties that are finite but too large to solve with: forces of
    order E (or K) times an area are squared in the residual norms, which overflow beyond
    about 1e154 (E = 1e300 used to end as "diverged", residual inf)."""
    limit = MAX_MODULUS
    for i, body in enumerate(scene.bodies):
        if body.E > limit:
            raise ModelError(f"body.{i}.E = {body.E:g} is too large to solve with (forces "
                             f"of order E times an area are squared in the residual norm, "
                             f"which overflows): at most {limit:g}; use other units")
    for i, pair in enumerate(scene.contacts):
        for key in ("K", "stick_slope"):
            value = getattr(pair, key)
            if isinstance(value, (int, float)) and value > limit:
                raise ModelError(f"contact.{i}.{key} = {value:g} is too large to solve with "
                                 f"(the contact forces are squared in the residual norm, "
                                 f"which overflows): at most {limit:g}; use other units")


def check_held(scene: Any, group_bodies: Mapping[str, Sequence[str]]) -> None:
    """Refuse a body that nothing holds against rigid motion in some step: no displacement
    constraint on any of its groups, and no contact pair joining it (through other bodies)
    to a constrained body or to an obstacle whose translation is prescribed.
    ``group_bodies``: the mesh's group -> the bodies it lies on."""
    rigids = {r.name for r in scene.rigids}
    parent = {name: name for name in [b.name for b in scene.bodies] + sorted(rigids)}

    def root(name: str) -> str:
        while parent[name] != name:
            name = parent[name]
        return name

    def owners(group: str) -> list[str]:
        return [group] if group in rigids else list(group_bodies.get(group, ()))

    for pair in scene.contacts:  # a contact pair could hold either side by the other
        ends = owners(pair.slave) + owners(pair.master)
        for other in ends[1:]:
            parent[root(other)] = root(ends[0])
    bcs: dict[str, tuple] = {}
    forced: dict[str, bool] = {}  # rigid obstacle -> force-controlled (else prescribed)
    for k, step in enumerate(scene.steps):
        bcs.update({bc.on: bc.u for bc in step.bcs})
        forced.update({r.name: r.force is not None for r in step.rigid})
        held = {root(name) for group, u in bcs.items() if any(c is not None for c in u)
                for name in owners(group)}
        held |= {root(r) for r in rigids if not forced.get(r, False)}
        for i, body in enumerate(scene.bodies):
            if root(body.name) not in held:
                raise ModelError(
                    f"body.{i} ({body.name!r}) is not held against rigid motion in step "
                    f"{k}: no displacement constraint on any of its groups, and no contact "
                    f"pair joins it to a constrained body or a prescribed obstacle")


def check_bcs(scene: Any, fields: Sequence[Any], group_bodies: Mapping[str, Sequence[str]],
              comm: Any) -> None:
    """Refuse bc groups that overlap and prescribe different values of a component to
    their shared nodes, in any step (bcs persist into later steps).  Collective on
    ``comm``; ``fields`` the bodies' fields, in the scene's body order."""
    index_of = {f.body.name: k for k, f in enumerate(fields)}
    nodes = {}  # group -> [(field index, owned nodes of the group on that body)]
    state: dict[str, tuple] = {}
    for index, step in enumerate(scene.steps):
        state.update({bc.on: bc.u for bc in step.bcs})
        for group in state:
            if group not in nodes:
                nodes[group] = [(index_of[b], fields[index_of[b]].owned_group_nodes(group))
                                for b in group_bodies.get(group, ())]
        conflicts = [_conflicts(state, nodes, k, f) for k, f in enumerate(fields)]
        if not comm.allreduce(int(any(c.any() for c in conflicts))):
            continue
        found = {(group, "xyz"[c]) for group, comps in state.items()
                 for k, owned in nodes[group] for c, value in enumerate(comps)
                 if value is not None and conflicts[k][owned, c].any()}
        found = sorted(set().union(*comm.allgather(found)))
        groups = sorted({g for g, _ in found})
        axes = "".join(sorted({a for _, a in found}))
        raise ModelError(f"step.{index}: bc groups {', '.join(map(repr, groups))} overlap and "
                         f"prescribe different values of component(s) {axes} to shared nodes")


def _conflicts(state: Mapping[str, tuple], nodes: Mapping[str, list], k: int,
               field: Any) -> Any:
    """(n_owned, gdim) bool: the components of body ``k``'s owned nodes given different
    values by the bcs in ``state`` (their spread beyond round-off)."""
    import numpy as np  # (not for reading a scene: it is answered before numpy loads)
    shape = (field.n_owned, field.gdim)
    total, total_sq, count = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    for group, comps in state.items():
        for body, owned in nodes[group]:
            if body != k:
                continue
            for c, value in enumerate(comps):
                if value is not None:
                    np.add.at(total[:, c], owned, value)
                    np.add.at(total_sq[:, c], owned, value * value)
                    np.add.at(count[:, c], owned, 1.0)
    mean = np.divide(total, count, out=np.zeros(shape), where=count > 0)
    spread = np.divide(total_sq, count, out=np.zeros(shape), where=count > 0) - mean ** 2
    return spread > 1e-24 * np.maximum(1.0, mean ** 2)
