"""Scene files: TOML → validated :mod:`dolfinx_friction.model` objects.

The format is the contract of ``shared/scene-format.md`` (version 2).  This
module is pure Python (no dolfinx): it checks everything that can be checked
without the mesh — key names, types, ranges, references between sections and
the consistency of vector lengths across the scene.  What needs the mesh
(group names, the geometric dimension, overlapping bc groups) is checked by
the mesh loader.

Every problem raises :class:`SceneError` with a one-line message naming the
file, the dotted key path (arrays indexed from 0) and what is wrong::

    scene.toml: contact.0.mu = -0.1: must be >= 0
"""
from __future__ import annotations

import difflib
import json
import math
import operator
import re
import tomllib
from collections import Counter
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, NoReturn, Optional, Union

from dolfinx_friction.model import (
    BC,
    CALCULIX,
    LAWS,
    MODELS,
    SHAPES,
    TANGENTS,
    Body,
    ContactPair,
    Load,
    Output,
    Rigid,
    RigidMotion,
    Scene,
    Step,
)

__all__ = ["SceneError", "load_scene", "parse_scene", "apply_override", "default_output_dir"]

PathLike = Union[str, Path]


class SceneError(ValueError):
    """An invalid scene: ``<file>: <key path> [= <value>]: <what is wrong>``.

    Attributes: ``key`` (dotted path or None), ``source`` (file or None) and
    ``detail`` (the message without the file).
    """

    def __init__(self, detail: str, *, key: Optional[str] = None, source: Optional[str] = None):
        self.detail = detail
        self.key = key
        self.source = source
        super().__init__(f"{source}: {detail}" if source else detail)

    def with_source(self, source: PathLike) -> "SceneError":
        return SceneError(self.detail, key=self.key, source=str(source))


# --------------------------------------------------------------------------- messages

_NO_VALUE = object()


def _show(value: Any, limit: int = 60) -> str:
    """A value as TOML would spell it, shortened for a one-line message."""
    text = _toml(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _toml(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(value)


def _fail(key: str, problem: str, value: Any = _NO_VALUE) -> NoReturn:
    subject = key if value is _NO_VALUE else f"{key} = {_show(value)}"
    raise SceneError(f"{subject}: {problem}" if subject else problem, key=key or None)


def _suggest(word: str, candidates: Sequence[str]) -> str:
    close = difflib.get_close_matches(word, list(candidates), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _join(prefix: str, name: Union[str, int]) -> str:
    return f"{prefix}.{name}" if prefix else str(name)


def _array_name(key: str) -> str:
    """``step.0.bc`` → ``step.bc`` (how the array is written in TOML)."""
    return re.sub(r"\.\d+", "", key)


# --------------------------------------------------------------------------- value checks
#
# A check takes (value, key path) and returns the converted value or calls _fail.

Check = Callable[[Any, str], Any]

_BOUNDS = (("gt", operator.gt, ">"), ("ge", operator.ge, ">="), ("lt", operator.lt, "<"))


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _number(**bounds: float) -> Check:
    """A finite int or float (bool is not a number), within ``gt``/``ge``/``lt`` bounds."""

    def check(value: Any, key: str) -> float:
        if not _is_number(value):
            _fail(key, "must be a number", value)
        try:
            x = float(value)
        except OverflowError:  # an integer beyond the float range
            x = math.inf
        if not math.isfinite(x):
            _fail(key, "must be finite", value)
        for name, holds, symbol in _BOUNDS:
            if name in bounds and not holds(x, bounds[name]):
                _fail(key, f"must be {symbol} {bounds[name]:g}", value)
        return x

    return check


def _integer(minimum: int, maximum: int, why: str = "") -> Check:
    """An int within ``[minimum, maximum]``; ``why`` explains the maximum."""

    def check(value: Any, key: str) -> int:
        if not isinstance(value, int) or isinstance(value, bool):
            _fail(key, "must be an integer", value)
        if value < minimum:
            _fail(key, f"must be >= {minimum}", value)
        if value > maximum:
            _fail(key, f"must be <= {maximum}" + (f" ({why})" if why else ""), value)
        return value

    return check


def _modulus(value: Any, key: str) -> float:
    """Young's modulus: > 0, and small enough that the penalty 50 E is a finite number."""
    E = _number(gt=0)(value, key)
    if not math.isfinite(50.0 * E):
        _fail(key, "is so large that the penalty K = 50 E (CalculiX's default) overflows",
              value)
    return E


def _penalty(value: Any, key: str) -> Union[float, str]:
    """``K`` or ``stick_slope``: a number > 0, or ``"calculix"`` for CalculiX's rule."""
    if isinstance(value, str):
        if value == CALCULIX:
            return value
        _fail(key, f"must be a number > 0 or {_toml(CALCULIX)}" + _suggest(value, [CALCULIX]),
              value)
    return _number(gt=0)(value, key)


def _one_of(*options: Any) -> Check:
    def check(value: Any, key: str) -> Any:
        if type(value) is type(options[0]) and value in options:
            return value
        hint = _suggest(value, [str(o) for o in options]) if isinstance(value, str) else ""
        _fail(key, "must be one of " + ", ".join(_toml(o) for o in options) + hint, value)

    return check


def _string(value: Any, key: str) -> str:
    if not isinstance(value, str):
        _fail(key, "must be a string", value)
    return value


def _name(value: Any, key: str) -> str:
    if not _string(value, key).strip():
        _fail(key, "must be a non-empty string", value)
    return value


def _bool(value: Any, key: str) -> bool:
    if not isinstance(value, bool):
        _fail(key, "must be true or false", value)
    return value


def _names(value: Any, key: str) -> tuple[str, ...]:
    if not isinstance(value, list):
        _fail(key, "must be a list of group names", value)
    names = tuple(_name(v, _join(key, i)) for i, v in enumerate(value))
    for i, name in enumerate(names):
        if name in names[:i]:
            _fail(_join(key, i), "listed twice", name)
    return names


def _msh_file(value: Any, key: str) -> str:
    if not _name(value, key).lower().endswith(".msh"):
        _fail(key, "must be a Gmsh .msh file", value)
    return value


_ANY_NUMBER = _number()
_PRESSURE = _number(ge=0)


def _list_of_2_or_3(value: Any, key: str, what: str) -> list:
    if not isinstance(value, list) or len(value) not in (2, 3):
        _fail(key, f"must be a list of 2 or 3 {what}", value)
    return value


def _vector(nonzero: bool = False) -> Check:
    """A vector of 2 or 3 numbers (the mesh dimension is checked across the scene)."""

    def check(value: Any, key: str) -> tuple[float, ...]:
        items = _list_of_2_or_3(value, key, "numbers")
        vector = tuple(_ANY_NUMBER(v, _join(key, i)) for i, v in enumerate(items))
        if nonzero and not any(vector):
            _fail(key, "must not be the zero vector", value)
        return vector

    return check


def _component(value: Any, key: str) -> Optional[float]:
    if value == "free":
        return None
    if not _is_number(value):
        _fail(key, 'must be a number or "free"', value)
    return _ANY_NUMBER(value, key)


def _displacement(value: Any, key: str) -> tuple[Optional[float], ...]:
    items = _list_of_2_or_3(value, key, 'components (numbers or "free")')
    return tuple(_component(v, _join(key, i)) for i, v in enumerate(items))


def _pressure_table(value: Any, key: str) -> tuple[tuple[float, float], ...]:
    """Tabular law: >= 2 ``[pressure, overclosure]`` pairs, overclosure non-decreasing.

    Equal consecutive overclosures are accepted: the law separates them by 1e-10
    as CalculiX does (contact-theory.md §4.1).
    """
    if not isinstance(value, list) or len(value) < 2:
        _fail(key, "must be a list of at least 2 [pressure, overclosure] pairs", value)
    pairs = []
    for i, pair in enumerate(value):
        where = _join(key, i)
        if not isinstance(pair, list) or len(pair) != 2:
            _fail(where, "must be a [pressure, overclosure] pair", pair)
        pairs.append((_PRESSURE(pair[0], _join(where, 0)), _ANY_NUMBER(pair[1], _join(where, 1))))
    for i in range(1, len(pairs)):
        previous = pairs[i - 1][1]
        if pairs[i][1] < previous:
            _fail(f"{key}.{i}.1", f"overclosure must not decrease (previous: {previous:g})",
                  value[i][1])
        if pairs[i][0] <= pairs[i - 1][0]:
            _fail(f"{key}.{i}.0", "pressure must increase with the overclosure "
                  f"(previous: {pairs[i - 1][0]:g})", value[i][0])
    return tuple(pairs)


# --------------------------------------------------------------------------- tables


@dataclass(frozen=True)
class _Key:
    """One key of a TOML table: its check, whether it is required, its model field name."""

    check: Check
    required: bool = False
    field: Optional[str] = None


def _read(table: Any, key: str, schema: Mapping[str, _Key]) -> dict[str, Any]:
    """Check a table against its schema; return ``{model field: converted value}``."""
    if not isinstance(table, Mapping):
        _fail(key, "must be a table", table)
    for name in table:
        if name not in schema:
            hint = _suggest(name, list(schema)) or f" (valid: {', '.join(schema)})"
            _fail(_join(key, name), "unknown key" + hint)
    for name, spec in schema.items():
        if spec.required and name not in table:
            _fail(_join(key, name), "required key is missing")
    return {spec.field or name: spec.check(table[name], _join(key, name))
            for name, spec in schema.items() if name in table}


def _array(build: Check, *, min_length: int = 0) -> Check:
    """An array of tables (``[[name]]``), each read by ``build(table, "name.<i>")``."""

    def check(value: Any, key: str) -> tuple:
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            _fail(key, f"must be an array of tables ([[{_array_name(key)}]])", value)
        if len(value) < min_length:
            _fail(key, f"needs at least {min_length} [[{_array_name(key)}]]", value)
        return tuple(build(item, _join(key, i)) for i, item in enumerate(value))

    return check


def _record(cls: type, schema: Mapping[str, _Key], *checks: Callable[[Any, str], None]) -> Check:
    """A table read into the dataclass ``cls``, then cross-checked by ``checks``."""

    def build(table: Any, key: str) -> Any:
        obj = cls(**_read(table, key, schema))
        for cross_check in checks:
            cross_check(obj, key)
        return obj

    return build


def _exactly_one(first: str, second: str) -> Callable[[Any, str], None]:
    def check(obj: Any, key: str) -> None:
        given = [name for name in (first, second) if getattr(obj, name) is not None]
        if len(given) != 1:
            _fail(key, f"needs exactly one of {first!r} and {second!r}"
                  + (" (both given)" if given else ""))

    return check


# ---- [[rigid]]

_SHAPE_KEYS = {"plane": ("point", "normal"), "sphere": ("center", "radius"),
               "cylinder": ("point", "axis", "radius")}
assert set(_SHAPE_KEYS) == set(SHAPES)
_GEOMETRY_KEYS = ("point", "normal", "center", "axis", "radius")


def _check_shape(rigid: Rigid, key: str) -> None:
    needed = _SHAPE_KEYS[rigid.shape]
    for name in _GEOMETRY_KEYS:
        given = getattr(rigid, name) is not None
        if name in needed and not given:
            _fail(_join(key, name), f"required for shape {rigid.shape!r}")
        if name not in needed and given:
            _fail(_join(key, name), f"not a parameter of shape {rigid.shape!r} "
                  f"(it takes {', '.join(needed)})", getattr(rigid, name))


_RIGID = _record(Rigid, {
    "name": _Key(_name, required=True),
    "shape": _Key(_one_of(*SHAPES), required=True),
    "point": _Key(_vector()),
    "normal": _Key(_vector(nonzero=True)),
    "center": _Key(_vector()),
    "axis": _Key(_vector(nonzero=True)),
    "radius": _Key(_number(gt=0)),
}, _check_shape)

# ---- [[contact]]

#: The keys a law cannot do without (the others have defaults, contact-theory.md §8).
#: Keys of other laws are accepted and unused, so a sweep may switch ``law`` alone.
_LAW_REQUIRES = {"exponential": ("p0",), "tabular": ("table",)}


def _check_law(pair: ContactPair, key: str) -> None:
    for name in _LAW_REQUIRES.get(pair.law, ()):
        if getattr(pair, name) is None:
            _fail(_join(key, name), f"required by law {pair.law!r}")


def _check_not_self_contact(pair: ContactPair, key: str) -> None:
    if pair.slave == pair.master:
        _fail(_join(key, "master"), "must differ from the slave", pair.master)


_CONTACT = _record(ContactPair, {
    "slave": _Key(_name, required=True),
    "master": _Key(_name, required=True),
    "law": _Key(_one_of(*LAWS)),
    "K": _Key(_penalty),
    "sigma_inf": _Key(_number(gt=0)),
    "c0": _Key(_number(gt=0)),
    "p0": _Key(_number(ge=0)),
    "table": _Key(_pressure_table),
    "mu": _Key(_number(ge=0)),
    "stick_slope": _Key(_penalty),
    "tangent": _Key(_one_of(*TANGENTS)),
    "pairing_iterations": _Key(_integer(1, 10_000)),
}, _check_law, _check_not_self_contact)

# ---- [[step]]

_BC = _record(BC, {"on": _Key(_name, required=True), "u": _Key(_displacement, required=True)})
_LOAD = _record(Load, {
    "on": _Key(_name, required=True),
    "traction": _Key(_vector()),
    "pressure": _Key(_ANY_NUMBER),
}, _exactly_one("traction", "pressure"))
_MOTION = _record(RigidMotion, {
    "name": _Key(_name, required=True),
    "displacement": _Key(_vector()),
    "force": _Key(_vector()),
}, _exactly_one("displacement", "force"))

_STEP_KEYS = {
    "name": _Key(_name),
    "increments": _Key(_integer(1, 1_000_000)),
    "max_cutbacks": _Key(_integer(0, 50, "an increment halved more often is below the "
                                        "resolution of the pseudo-time")),
    "newton_rtol": _Key(_number(gt=0)),
    "newton_atol": _Key(_number(gt=0)),
    "max_iterations": _Key(_integer(1, 10_000)),
    "line_search": _Key(_bool),
    "bc": _Key(_array(_BC), field="bcs"),
    "load": _Key(_array(_LOAD), field="loads"),
    "rigid": _Key(_array(_MOTION), field="rigid"),
}


def _check_once_per_step(items: Sequence[Any], key: str, attr: str) -> None:
    """Within one step a group (or obstacle) is named by at most one entry of a kind."""
    first: dict[str, int] = {}
    for j, item in enumerate(items):
        name = getattr(item, attr)
        if name in first:
            _fail(_join(_join(key, j), attr), f"already given in this step by "
                  f"{_join(key, first[name])}", name)
        first[name] = j


def _step(table: Any, key: str) -> Step:
    fields = _read(table, key, _STEP_KEYS)
    fields.setdefault("name", "step-" + key.rsplit(".", 1)[-1])
    step = Step(**fields)
    _check_once_per_step(step.bcs, _join(key, "bc"), "on")
    _check_once_per_step(step.loads, _join(key, "load"), "on")
    _check_once_per_step(step.rigid, _join(key, "rigid"), "name")
    return step


# ---- the whole scene

_BODY = _record(Body, {
    "name": _Key(_name, required=True),
    "E": _Key(_modulus, required=True),
    "nu": _Key(_number(gt=-1, lt=0.5), required=True),
    "degree": _Key(_one_of(1, 2)),
    "plane": _Key(_one_of("strain", "stress")),
    "thickness": _Key(_number(gt=0)),
    "model": _Key(_one_of(*MODELS)),
})
_OUTPUT = _record(Output, {
    "dir": _Key(_name),
    "reactions": _Key(_names),
    "fields": _Key(_bool),
    "contact_table": _Key(_bool),
})


def _mesh(table: Any, key: str) -> str:
    return _read(table, key, {"file": _Key(_msh_file, required=True)})["file"]


_SCENE_KEYS = {
    "title": _Key(_string),
    "mesh": _Key(_mesh, required=True),
    "body": _Key(_array(_BODY, min_length=1), required=True, field="bodies"),
    "rigid": _Key(_array(_RIGID), field="rigids"),
    "contact": _Key(_array(_CONTACT), field="contacts"),
    "step": _Key(_array(_step, min_length=1), required=True, field="steps"),
    "output": _Key(_OUTPUT),
}


def _check_unique_names(items: Sequence[Any], key: str) -> None:
    first: dict[str, int] = {}
    for i, item in enumerate(items):
        if item.name in first:
            _fail(_join(_join(key, i), "name"), f"duplicate name (also {key}.{first[item.name]})",
                  item.name)
        first[item.name] = i


def _check_contacts(scene: Scene) -> None:
    rigids = {r.name for r in scene.rigids}
    seen: dict[tuple[str, str], int] = {}
    for i, pair in enumerate(scene.contacts):
        if pair.slave in rigids:
            _fail(f"contact.{i}.slave", "names a [[rigid]] obstacle; a slave must be a facet group",
                  pair.slave)
        first = seen.setdefault((pair.slave, pair.master), i)
        if first != i:
            _fail(f"contact.{i}", f"same slave and master as contact.{first}")


def _check_models(scene: Scene) -> None:
    for i, body in enumerate(scene.bodies):
        if body.finite_strain and body.plane == "stress":
            _fail(f"body.{i}.plane", f"plane stress is not available at finite strain (model "
                  f"{body.model!r}): use plane strain or a 3D mesh", body.plane)


def _check_rigid_motions(scene: Scene) -> None:
    rigids = [r.name for r in scene.rigids]
    for i, step in enumerate(scene.steps):
        for j, motion in enumerate(step.rigid):
            if motion.name not in rigids:
                _fail(f"step.{i}.rigid.{j}.name", "no [[rigid]] of that name"
                      + _suggest(motion.name, rigids), motion.name)


def _vectors(scene: Scene) -> Iterator[tuple[str, tuple]]:
    """Every vector of the scene with its key path."""
    for i, rigid in enumerate(scene.rigids):
        for name in ("point", "normal", "center", "axis"):
            if getattr(rigid, name) is not None:
                yield f"rigid.{i}.{name}", getattr(rigid, name)
    for i, step in enumerate(scene.steps):
        for j, bc in enumerate(step.bcs):
            yield f"step.{i}.bc.{j}.u", bc.u
        for j, load in enumerate(step.loads):
            if load.traction is not None:
                yield f"step.{i}.load.{j}.traction", load.traction
        for j, motion in enumerate(step.rigid):
            for name in ("displacement", "force"):
                if getattr(motion, name) is not None:
                    yield f"step.{i}.rigid.{j}.{name}", getattr(motion, name)


def _check_dimension(scene: Scene) -> None:
    """All vectors have one length, the (yet unknown) mesh dimension; cylinders are 3D.

    The dimension is the most common length (the first one on a tie), so the
    message blames the odd vector out.
    """
    vectors = list(_vectors(scene))
    if not vectors:
        return
    lengths = Counter(len(vector) for _, vector in vectors)
    dim = lengths.most_common(1)[0][0]
    example = next(key for key, vector in vectors if len(vector) == dim)
    for key, vector in vectors:
        if len(vector) != dim:
            _fail(key, f"has {len(vector)} components but {example} has {dim} "
                  "(every vector has the mesh dimension)")
    if dim == 2:
        for i, rigid in enumerate(scene.rigids):
            if rigid.shape == "cylinder":
                _fail(f"rigid.{i}.shape", f"is 3D only, but {example} has 2 components",
                      rigid.shape)


def _check_scene(scene: Scene) -> None:
    _check_unique_names(scene.bodies, "body")
    _check_unique_names(scene.rigids, "rigid")
    _check_unique_names(scene.steps, "step")
    _check_contacts(scene)
    _check_models(scene)
    _check_rigid_motions(scene)
    _check_dimension(scene)


#: How deeply arrays and tables may nest (a scene needs 5 levels).
MAX_DEPTH = 32


def _check_depth(data: Mapping[str, Any]) -> None:
    """Refuse values nested more than MAX_DEPTH levels (before anything recurses into them)."""
    stack: list[tuple[Any, str, int]] = [(data, "", 0)]
    while stack:
        node, key, depth = stack.pop()
        if depth > MAX_DEPTH:
            _fail(".".join(key.split(".")[:4]) + "...", f"nested more than {MAX_DEPTH} levels deep")
        items = (node.items() if isinstance(node, Mapping) else
                 enumerate(node) if isinstance(node, (list, tuple)) else ())
        stack.extend((v, _join(key, k), depth + 1) for k, v in items)


def _resolve(base: Optional[Path], name: str) -> Path:
    return (base / name).resolve() if base is not None else Path(name)


def parse_scene(data: Mapping[str, Any], source: Optional[PathLike] = None) -> Scene:
    """Validate a scene read from TOML and build the model objects.

    ``source`` is the scene file: relative paths (``mesh.file``, ``output.dir``)
    are resolved against its directory and messages name it.  Without a source
    the paths are kept as written.
    """
    try:
        if not isinstance(data, Mapping):
            raise SceneError("a scene must be a table of keys")
        _check_depth(data)
        fields = _read(data, "", _SCENE_KEYS)
    except SceneError as error:
        raise (error.with_source(source) if source is not None else error) from None
    base = Path(source).absolute().parent if source is not None else None
    fields["mesh"] = _resolve(base, fields["mesh"])
    output = fields.get("output", Output())
    if output.dir is not None:
        fields["output"] = replace(output, dir=_resolve(base, output.dir))
    scene = Scene(**fields, source=Path(source).resolve() if source is not None else None)
    try:
        _check_scene(scene)
    except SceneError as error:
        raise (error.with_source(source) if source is not None else error) from None
    return scene


# --------------------------------------------------------------------------- --set


def parse_value(text: str) -> Any:
    """``VALUE`` of ``--set KEY=VALUE``: a TOML value if it parses as one, else the bare string."""
    try:
        document = tomllib.loads(f"value = {text}")
    except (tomllib.TOMLDecodeError, RecursionError):
        return text
    return document["value"] if list(document) == ["value"] else text


def _index(array: list, segment: str, path: str) -> int:
    if not re.fullmatch(r"[0-9]+", segment):
        raise SceneError(f"{path}: {segment!r} is not an array index (arrays are indexed from 0)",
                         key=path)
    index = int(segment)
    if index >= len(array):
        owner = path.rpartition(".")[0] or "the array"
        raise SceneError(f"{path}: index {index} out of range ({owner} has {len(array)} entries)",
                         key=path)
    return index


def _child(node: Any, segment: str, path: str, parent: str, create: bool) -> Any:
    """The entry ``segment`` of a table or array; a missing table is created if ``create``."""
    if isinstance(node, list):
        return node[_index(node, segment, path)]
    if not isinstance(node, dict):
        raise SceneError(f"{path}: {parent} = {_show(node)} is neither a table nor an array",
                         key=path)
    if segment not in node:
        if not create:
            raise SceneError(f"{path}: no such key", key=path)
        node[segment] = {}
    return node[segment]


def apply_override(data: dict, assignment: str) -> None:
    """Apply one ``KEY=VALUE`` (dotted path, arrays indexed from 0) to ``data`` in place.

    Intermediate tables must exist, except that a missing table is created when
    the next segment is a key (``output.fields=false`` on a scene without
    ``[output]``); array entries must exist.  The last key of a table may be
    absent.  The result is validated afterwards like any scene.
    """
    key, sep, text = assignment.partition("=")
    key = key.strip()
    try:
        if not sep or not key:
            raise SceneError("expected KEY=VALUE")
        segments = key.split(".")
        if not all(segments):
            raise SceneError(f"{key}: empty key segment", key=key)
        node: Any = data
        for depth, segment in enumerate(segments[:-1]):
            create = not segments[depth + 1].isdigit()
            node = _child(node, segment, ".".join(segments[: depth + 1]),
                          ".".join(segments[:depth]) or "the scene", create)
        last = segments[-1]
        if isinstance(node, list):
            node[_index(node, last, key)] = parse_value(text.strip())
        elif isinstance(node, dict):
            node[last] = parse_value(text.strip())
        else:
            parent = ".".join(segments[:-1])
            raise SceneError(f"{key}: {parent} = {_show(node)} is neither a table nor an array",
                             key=key)
    except SceneError as error:
        raise SceneError(f"--set {assignment}: {error.detail}", key=error.key) from None


# --------------------------------------------------------------------------- files


_BOM = b"\xef\xbb\xbf"


def _read_toml(path: Path, label: str) -> dict:
    """The TOML document of ``path`` (a UTF-8 byte-order mark is skipped)."""
    try:
        with open(path, "rb") as stream:
            data = stream.read()
        return tomllib.loads(data.removeprefix(_BOM).decode("utf-8"))
    except OSError as error:
        reason = error.strerror or str(error)
        raise SceneError(f"cannot read the scene: {reason}", source=label) from None
    except UnicodeDecodeError as error:
        raise SceneError(f"not UTF-8 text ({error.reason})", source=label) from None
    except RecursionError:
        raise SceneError(f"TOML nested too deeply to read (at most {MAX_DEPTH} levels of "
                         "arrays and tables)", source=label) from None
    except tomllib.TOMLDecodeError as error:
        message = str(error)
        match = re.search(r"\(at line (\d+), column (\d+)\)$", message)
        if match:
            message = message[: match.start()].rstrip()
            label = f"{label}:{match.group(1)}:{match.group(2)}"
        raise SceneError(f"TOML syntax error: {message}", source=label) from None


def load_scene(path: PathLike, overrides: Sequence[str] = ()) -> Scene:
    """Read a scene file, apply ``--set`` overrides, validate.  Raises :class:`SceneError`."""
    data = _read_toml(Path(path), str(path))
    for assignment in overrides:
        try:
            apply_override(data, assignment)
        except SceneError as error:
            raise error.with_source(path) from None
    return replace(parse_scene(data, source=path), overrides=tuple(overrides))


def default_output_dir(scene: Scene) -> Path:
    """``output.dir``, else ``<scene stem>_results`` next to the scene file.

    A scene built in Python (no source file) defaults to ``./results``.
    """
    if scene.output.dir is not None:
        return Path(scene.output.dir)
    if scene.source is not None:
        source = Path(scene.source)
        return source.parent / f"{source.stem}_results"
    return Path.cwd() / "results"
