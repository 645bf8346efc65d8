"""Scene files: TOML → validated :mod:`dolfinx_friction.scene.model` objects.

The format is that of ``docs/scene-format.md`` (versions 1 to 3).  This
module is pure Python (no dolfinx): it checks the TOML structure (key names,
required keys, tables and arrays of tables) and builds the model dataclasses,
which check the values and the scene as a whole by the rules they share with
the Python API (:mod:`dolfinx_friction.scene.validation`): types, ranges, references
between sections and the consistency of vector lengths across the scene.  What
needs the mesh (group names, the geometric dimension, overlapping bc groups) is
checked by the mesh loader.

Every problem raises :class:`SceneError` with a one-line message naming the
file, the dotted key path (arrays indexed from 0) and what is wrong::

    scene.toml: contact.0.mu = -0.1: must be >= 0
"""
from __future__ import annotations

import re
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any, Optional, Union

from dolfinx_friction.scene.model import (
    BC,
    RULES,
    Body,
    ContactPair,
    Load,
    Output,
    Rigid,
    RigidMotion,
    Scene,
    SolverSettings,
    Step,
)
from dolfinx_friction.scene.validation import (
    Key,
    SceneError,
    array_name,
    fail,
    join,
    msh_file,
    place,
    show,
    suggest,
)

__all__ = ["SceneError", "load_scene", "parse_scene", "apply_override", "default_output_dir"]

PathLike = Union[str, Path]

# --------------------------------------------------------------------------- tables
#
# The values are checked by the dataclasses (model.RULES); the reader checks the TOML
# structure: key names, required keys, tables and arrays of tables.

Reader = Callable[[Any, str], Any]


def _read(table: Any, key: str, keys: Mapping[str, Key],
          nested: Mapping[str, Reader]) -> dict[str, Any]:
    """Check the key names of a table; return ``{field: value}``, the ``nested`` tables and
    arrays read by their readers, the other values as written."""
    if not isinstance(table, Mapping):
        fail(key, "must be a table", table)
    for name in table:
        if name not in keys:
            hint = suggest(name, list(keys)) or f" (valid: {', '.join(keys)})"
            fail(join(key, name), "unknown key" + hint)
    for name, spec in keys.items():
        if spec.required and name not in table:
            fail(join(key, name), "required key is missing")
    return {spec.field or name: nested[name](table[name], join(key, name)) if name in nested
            else table[name] for name, spec in keys.items() if name in table}


def _build(cls: type, fields: dict[str, Any], key: str) -> Any:
    """``cls(**fields)``, its messages naming ``key``."""
    with place(key):
        return cls(**fields)


def _record(cls: type, nested: Optional[Mapping[str, Reader]] = None) -> Reader:
    """A table read into the dataclass ``cls``."""

    def build(table: Any, key: str) -> Any:
        return _build(cls, _read(table, key, RULES[cls].keys, nested or {}), key)

    return build


def _array(build: Reader, *, min_length: int = 0) -> Reader:
    """An array of tables (``[[name]]``), each read by ``build(table, "name.<i>")``."""

    def check(value: Any, key: str) -> tuple:
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            fail(key, f"must be an array of tables ([[{array_name(key)}]])", value)
        if len(value) < min_length:
            fail(key, f"needs at least {min_length} [[{array_name(key)}]]", value)
        return tuple(build(item, join(key, i)) for i, item in enumerate(value))

    return check


_STEP_ARRAYS = {"bc": _array(_record(BC)), "load": _array(_record(Load)),
                "rigid": _array(_record(RigidMotion))}


def _step(table: Any, key: str) -> Step:
    fields = _read(table, key, RULES[Step].keys, _STEP_ARRAYS)
    fields.setdefault("name", "step-" + key.rsplit(".", 1)[-1])
    return _build(Step, fields, key)


def _mesh(table: Any, key: str) -> str:
    return _read(table, key, {"file": Key(msh_file, required=True)}, {"file": msh_file})["file"]


_SCENE_TABLES = {
    "mesh": _mesh,
    "body": _array(_record(Body), min_length=1),
    "rigid": _array(_record(Rigid)),
    "contact": _array(_record(ContactPair)),
    "step": _array(_step, min_length=1),
    "output": _record(Output),
    "solver": _record(SolverSettings),
}


#: How deeply arrays and tables may nest (a scene needs 5 levels).
MAX_DEPTH = 32


def _check_depth(data: Mapping[str, Any]) -> None:
    """Refuse values nested more than MAX_DEPTH levels (before anything recurses into them)."""
    stack: list[tuple[Any, str, int]] = [(data, "", 0)]
    while stack:
        node, key, depth = stack.pop()
        if depth > MAX_DEPTH:
            fail(".".join(key.split(".")[:4]) + "...", f"nested more than {MAX_DEPTH} levels deep")
        items = (node.items() if isinstance(node, Mapping) else
                 enumerate(node) if isinstance(node, (list, tuple)) else ())
        stack.extend((v, join(key, k), depth + 1) for k, v in items)


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
        fields = _read(data, "", RULES[Scene].keys, _SCENE_TABLES)
        base = Path(source).absolute().parent if source is not None else None
        fields["mesh"] = _resolve(base, fields["mesh"])
        output = fields.get("output", Output())
        if output.dir is not None:
            fields["output"] = replace(output, dir=_resolve(base, output.dir))
        fields["source"] = None if source is None else Path(source).resolve()
        return _build(Scene, fields, "")
    except SceneError as error:
        raise (error.with_source(source) if source is not None else error) from None


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
        raise SceneError(f"{path}: {parent} = {show(node)} is neither a table nor an array",
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
            raise SceneError(f"{key}: {parent} = {show(node)} is neither a table nor an array",
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
