"""The rules engine of the library's inputs: checks of single values (numbers, ranges,
strings, ...) with one-line messages naming the key, and the :class:`Rules` of a frozen
dataclass (:func:`validate`, from ``__post_init__``).

Standard library only, below every layer: the scene's dataclasses
(:mod:`dolfinx_friction.scene.model`, their scene-specific rules in
:mod:`dolfinx_friction.scene.validation`) and the building block's contact settings
(:mod:`dolfinx_friction.fem.contact_settings`) are held to the same checks and messages.
Every problem raises :class:`SceneError`: ``<key path> [= <value>]: <what is wrong>``.
"""
from __future__ import annotations

import contextlib
import dataclasses
import difflib
import json
import math
import numbers
import operator
import re
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextvars import ContextVar
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn


class SceneError(ValueError):
    """An invalid scene: ``<file>: <key path> [= <value>]: <what is wrong>``.

    Attributes: ``key`` (dotted path or None), ``source`` (file or None) and
    ``detail`` (the message without the file).
    """

    def __init__(self, detail: str, *, key: str | None = None, source: str | None = None):
        self.detail = detail
        self.key = key
        self.source = source
        super().__init__(f"{source}: {detail}" if source else detail)

    def with_source(self, source: str | Path) -> SceneError:
        return SceneError(self.detail, key=self.key, source=str(source))


# --------------------------------------------------------------------------- messages

_NO_VALUE = object()
#: ``K = "calculix"``, ``stick_slope = "calculix"``: CalculiX's rules, 50 E and E/2.
CALCULIX = "calculix"


def show(value: Any, limit: int = 60) -> str:
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


def fail(key: str, problem: str, value: Any = _NO_VALUE) -> NoReturn:
    """Raise the :class:`SceneError` ``<key> [= <value>]: <problem>``."""
    subject = key if value is _NO_VALUE else f"{key} = {show(value)}"
    raise SceneError(f"{subject}: {problem}" if subject else problem, key=key or None)


def suggest(word: str, candidates: Sequence[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest candidate, or an empty string."""
    close = difflib.get_close_matches(word, list(candidates), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def join(prefix: str, name: str | int) -> str:
    """The key path ``prefix.name`` (``name`` alone at the top level)."""
    return f"{prefix}.{name}" if prefix else str(name)


def array_name(key: str) -> str:
    """``step.0.bc`` → ``step.bc`` (how the array is written in TOML)."""
    return re.sub(r"\.\d+", "", key)


# --------------------------------------------------------------------------- value checks
#
# A check takes (value, key path) and returns the converted value or calls fail.

Check = Callable[[Any, str], Any]

_BOUNDS = (("gt", operator.gt, ">"), ("ge", operator.ge, ">="), ("lt", operator.lt, "<"))


def _is_number(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _is_list(value: Any) -> bool:
    """A TOML array, or in Python a list, tuple or numpy array."""
    return (isinstance(value, (list, tuple))
            or (hasattr(value, "tolist") and getattr(value, "ndim", 0) >= 1))


def number(**bounds: float) -> Check:
    """A finite int or float (bool is not a number), within ``gt``/``ge``/``lt`` bounds."""

    def check(value: Any, key: str) -> float:
        if not _is_number(value):
            fail(key, "must be a number", value)
        try:
            x = float(value)
        except OverflowError:  # an integer beyond the float range
            x = math.inf
        if not math.isfinite(x):
            fail(key, "must be finite", value)
        for name, holds, symbol in _BOUNDS:
            if name in bounds and not holds(x, bounds[name]):
                fail(key, f"must be {symbol} {bounds[name]:g}", value)
        return x

    return check


def integer(minimum: int, maximum: int, why: str = "") -> Check:
    """An int within ``[minimum, maximum]``; ``why`` explains the maximum."""

    def check(value: Any, key: str) -> int:
        if not isinstance(value, numbers.Integral) or isinstance(value, bool):
            fail(key, "must be an integer", value)
        if value < minimum:
            fail(key, f"must be >= {minimum}", value)
        if value > maximum:
            fail(key, f"must be <= {maximum}" + (f" ({why})" if why else ""), value)
        return int(value)

    return check


def modulus(value: Any, key: str) -> float:
    """Young's modulus: > 0, and small enough that the penalty 50 E is a finite number."""
    E = number(gt=0)(value, key)
    if not math.isfinite(50.0 * E):
        fail(key, "is so large that CalculiX's penalty rule K = 50 E overflows", value)
    return E


def penalty(value: Any, key: str) -> float | str:
    """``K`` or ``stick_slope``: a number > 0, or ``"calculix"`` for CalculiX's rule."""
    if isinstance(value, str):
        if value == CALCULIX:
            return value
        fail(key, f"must be a number > 0 or {_toml(CALCULIX)}" + suggest(value, [CALCULIX]),
             value)
    return number(gt=0)(value, key)


def one_of(*options: Any) -> Check:
    """One of ``options`` (of the same type: ``1.0`` is not the option ``1``)."""

    def check(value: Any, key: str) -> Any:
        if type(value) is type(options[0]) and value in options:
            return value
        hint = suggest(value, [str(o) for o in options]) if isinstance(value, str) else ""
        fail(key, "must be one of " + ", ".join(_toml(o) for o in options) + hint, value)

    return check


def string(value: Any, key: str) -> str:
    if not isinstance(value, str):
        fail(key, "must be a string", value)
    return value


def name(value: Any, key: str) -> str:
    """A non-empty string (a group, body, obstacle or step name)."""
    if not string(value, key).strip():
        fail(key, "must be a non-empty string", value)
    return value


def boolean(value: Any, key: str) -> bool:
    if not isinstance(value, bool):
        fail(key, "must be true or false", value)
    return value


ANY_NUMBER = number()
PRESSURE = number(ge=0)


# --------------------------------------------------------------------------- rules


@dataclass(frozen=True)
class Key:
    """One key of a scene-file table: its check, whether the file must give it, and the
    dataclass field it fills (its own name if None)."""

    check: Check
    required: bool = False
    field: str | None = None


@dataclass(frozen=True)
class Rules:
    """The rules of one dataclass: its scene-file table (the key path without indices,
    ``"step.bc"``), its keys in file order, and the checks across fields (``(obj, key)``)."""

    table: str
    keys: Mapping[str, Key]
    checks: tuple[Callable[[Any, str], None], ...] = ()


#: The key path of the object being built (set by the scene reader: ``contact.0``).
_PLACE: ContextVar[str | None] = ContextVar("place", default=None)


@contextlib.contextmanager
def place(key: str) -> Iterator[None]:
    """Name the objects built inside by ``key`` (the scene reader's indexed path)."""
    token = _PLACE.set(key)
    try:
        yield
    finally:
        _PLACE.reset(token)


def validate(obj: Any, rules: Rules) -> None:
    """Check and convert the fields of the frozen dataclass ``obj`` in place (from
    ``__post_init__``).  A field whose default is None may be None."""
    key = _PLACE.get()
    key = rules.table if key is None else key
    optional = {f.name for f in dataclasses.fields(obj) if f.default is None}
    for name_, spec in rules.keys.items():
        attr = spec.field or name_
        value = getattr(obj, attr)
        if value is None and attr in optional:
            continue
        object.__setattr__(obj, attr, spec.check(value, join(key, name_)))
    for check in rules.checks:
        check(obj, key)


# --------------------------------------------------------------------------- checks across fields


def exactly_one(first: str, second: str) -> Callable[[Any, str], None]:
    def check(obj: Any, key: str) -> None:
        given = [name_ for name_ in (first, second) if getattr(obj, name_) is not None]
        if len(given) != 1:
            fail(key, f"needs exactly one of {first!r} and {second!r}"
                 + (" (both given)" if given else ""))

    return check


def _list_of_2_or_3(value: Any, key: str, what: str) -> list:
    if not _is_list(value) or len(value) not in (2, 3):
        fail(key, f"must be a list of 2 or 3 {what}", value)
    return list(value)


def rotation(value: Any, key: str) -> tuple[float, ...]:
    """A rigid rotation [rad]: an angle (2D, counter-clockwise), stored as ``(theta,)`` (which
    reads back), or a rotation vector of 3 numbers (3D); the mesh dimension is checked
    across the scene."""
    if _is_number(value):
        return (ANY_NUMBER(value, key),)
    if not _is_list(value) or len(value) not in (1, 3):
        fail(key, "must be an angle (a number, 2D) or a rotation vector of 3 numbers (3D)",
             value)
    return tuple(ANY_NUMBER(v, join(key, i)) for i, v in enumerate(value))


def vector(nonzero: bool = False) -> Check:
    """A vector of 2 or 3 numbers (the mesh dimension is checked across the scene)."""

    def check(value: Any, key: str) -> tuple[float, ...]:
        items = _list_of_2_or_3(value, key, "numbers")
        result = tuple(ANY_NUMBER(v, join(key, i)) for i, v in enumerate(items))
        if nonzero and not any(result):
            fail(key, "must not be the zero vector", value)
        return result

    return check
