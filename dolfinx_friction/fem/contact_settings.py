"""A contact pair's settings: their rules and their defaults, in one place.

Pure Python (the rules engine :mod:`dolfinx_friction.rules`), no dolfinx: the scene's
``[[contact]]`` (:class:`~dolfinx_friction.scene.model.ContactPair`) and the keywords of
:class:`~dolfinx_friction.fem.node_to_surface.NodeToSurface` are checked by the same
:data:`KEYS` (the same one-line messages, ``contact.mu = -0.1: must be >= 0``) and get the
same defaults (:func:`defaults`).  ``K``, ``sigma_inf`` and ``stick_slope`` default with
the slave body's Young's modulus ``E`` and its node spacing ``h``; :data:`CALCULIX` asks
for CalculiX's rules.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from dolfinx_friction import rules as r
from dolfinx_friction.rules import CALCULIX, Key, Rules, validate

__all__ = [
    "CALCULIX",
    "DISTRIBUTIONS",
    "KEYS",
    "LAWS",
    "MAX_AUGMENTATIONS",
    "MAX_RELAXATION",
    "METHODS",
    "PENALTY_PER_SPACING",
    "STICK_SLOPE_PER_SPACING",
    "TANGENTS",
    "ContactSettings",
    "check_law",
    "defaults",
    "pressure_table",
]

LAWS = ("linear", "exponential", "tabular", "hard")
TANGENTS = ("consistent", "calculix")
#: "penalty": the law's overclosure and the stick's elastic slip stay (small, with K and
#: lambda); "augmented": Uzawa updates of multipliers remove them to a tolerance
METHODS = ("penalty", "augmented")
#: how a slave node's force reaches a deformable master's nodes: "nodal" with the master
#: face's shape functions at the node's projection (node-to-surface), "mortar" with the
#: mortar weights of the slave faces around the node (docs/theory.md §2.4)
DISTRIBUTIONS = ("nodal", "mortar")


def default_distribution(quadratic: bool, rigid: bool, axisymmetric: bool) -> str:
    """The distribution of a contact that gives none: ``"mortar"`` for quadratic slave
    faces on a deformable master (the patch test and pointwise pressures: docs/theory.md
    §2.1), ``"nodal"`` otherwise (a rigid master has one node; an axisymmetric body's
    quadratic faces pass the patch test with neither, §2.4)."""
    return "mortar" if quadratic and not rigid and not axisymmetric else "nodal"
#: augmented Lagrangian updates an increment may take; one that needs more is cut back (a
#: Uzawa update divides the violation by about 1 + K / (the structure's stiffness at a
#: node): 2-4 updates at the default K)
MAX_AUGMENTATIONS = 25
#: largest over-relaxation of an augmented Lagrangian update (Aitken's factor, 1 / (1 -
#: rho) on a geometric series of ratio rho: 100 reaches rho = 0.99, a penalty of about 0.01
#: times the structure's stiffness at a node)
MAX_RELAXATION = 100.0

#: Default penalty and stick slope in units of E/h (E: the slave body's Young's modulus,
#: h: its node spacing, see :func:`defaults`), from the stability maps
#: (benchmarks/stability/README.md).  K = 10 E/h is the stiffest decade at which every
#: K x increment map converges for every increment size and method (with line search
#: without a cutback); at 100 E/h frictional sliding fails or loses the contact, at
#: 1 E/h the overclosure reaches 4 % of the spacing (Hertz, ironing: the penetration
#: warning fires).  lambda = 1 E/h: the stiffest decade at which both stick slope x mu
#: maps converge for every mu with and without line search, the full-slip ratio within
#: 1 % of mu on the block (10 E/h: cutbacks and a lost contact on the ironing, 100 E/h
#: fails; <= 0.01 E/h does not mobilise the friction).
PENALTY_PER_SPACING = 10.0
STICK_SLOPE_PER_SPACING = 1.0


def pressure_table(value: Any, key: str) -> tuple[tuple[float, float], ...]:
    """Tabular law: >= 2 ``[pressure, overclosure]`` pairs, overclosure non-decreasing.

    Equal consecutive overclosures are accepted: the law separates them by 1e-10
    as CalculiX does (docs/theory.md §4.1).
    """
    if not r._is_list(value) or len(value) < 2:
        r.fail(key, "must be a list of at least 2 [pressure, overclosure] pairs", value)
    pairs = []
    for i, pair in enumerate(value):
        where = r.join(key, i)
        if not r._is_list(pair) or len(pair) != 2:
            r.fail(where, "must be a [pressure, overclosure] pair", pair)
        pairs.append((r.PRESSURE(pair[0], r.join(where, 0)),
                      r.ANY_NUMBER(pair[1], r.join(where, 1))))
    for i in range(1, len(pairs)):
        previous = pairs[i - 1][1]
        if pairs[i][1] < previous:
            r.fail(f"{key}.{i}.1", f"overclosure must not decrease (previous: {previous:g})",
                   value[i][1])
        if pairs[i][0] <= pairs[i - 1][0]:
            r.fail(f"{key}.{i}.0", "pressure must increase with the overclosure "
                   f"(previous: {pairs[i - 1][0]:g})", value[i][0])
    return tuple(pairs)


#: The keys a law cannot do without (the others have defaults, docs/theory.md §8).
#: Keys of other laws are accepted and unused, so a sweep may switch ``law`` alone.
_LAW_REQUIRES = {"exponential": ("p0",), "tabular": ("table",)}


def check_law(pair: Any, key: str) -> None:
    for name_ in _LAW_REQUIRES.get(pair.law, ()):
        if getattr(pair, name_) is None:
            r.fail(r.join(key, name_), f"required by law {pair.law!r}")


#: The rules of a contact's law and friction, by scene-file key in file order (the keys
#: of ``[[contact]]`` after ``slave`` and ``master``).
KEYS: dict[str, Key] = {
    "law": Key(r.one_of(*LAWS)),
    "K": Key(r.penalty),
    "sigma_inf": Key(r.number(gt=0)),
    "c0": Key(r.number(gt=0)),
    "p0": Key(r.number(ge=0)),
    "table": Key(pressure_table),
    "mu": Key(r.number(ge=0)),
    "stick_slope": Key(r.penalty),
    "tangent": Key(r.one_of(*TANGENTS)),
    "pairing_iterations": Key(r.integer(1, 10_000)),
    "method": Key(r.one_of(*METHODS)),
    "augmented_tolerance": Key(r.number(gt=0, lt=1)),
    "distribution": Key(r.one_of(*DISTRIBUTIONS)),
}


def defaults(settings: Any, E_slave: float, spacing: float | None = None) -> dict:
    """The settings of ``settings`` (a :class:`ContactSettings` or a scene ``ContactPair``)
    whose defaults depend on the slave body, resolved (docs/theory.md §8, scene-format.md
    version 2): ``law`` (``"hard"`` is ``"linear"``), ``K``, ``sigma_inf``, ``c0``,
    ``stick_slope``.

    ``sigma_inf = E/70000``, ``c0 = 1e-3``; with the slave node spacing ``h``
    (``spacing``, see :attr:`NodeToSurface.spacing`) also ``K = 10 E/h`` and
    ``stick_slope = E/h`` (:data:`PENALTY_PER_SPACING`, :data:`STICK_SLOPE_PER_SPACING`);
    :data:`CALCULIX` gives 50 E and E/2.  Without ``spacing`` a defaulted ``K`` and
    ``stick_slope`` stay ``None`` (the pressure laws other than linear need no ``h``).
    """
    def rule(value, per_spacing: float, calculix: float):
        if value == CALCULIX:
            return calculix * E_slave
        if value is None and spacing is not None:
            return per_spacing * E_slave / spacing
        return value

    sigma_inf = settings.sigma_inf
    return {"law": "linear" if settings.law == "hard" else settings.law,
            "K": rule(settings.K, PENALTY_PER_SPACING, 50.0),
            "sigma_inf": sigma_inf if sigma_inf is not None else E_slave / 70000.0,
            "c0": settings.c0 if settings.c0 is not None else 1e-3,
            "stick_slope": rule(settings.stick_slope, STICK_SLOPE_PER_SPACING, 0.5)}


@dataclass(frozen=True)
class ContactSettings:
    """A contact's law and friction as given (checked by :data:`KEYS`, under the table
    name ``contact``); ``None`` (or :data:`CALCULIX`) for a default still to be resolved
    (:meth:`resolved`)."""

    law: str = "linear"
    K: float | str | None = None  # None: the default; CALCULIX: 50 E
    sigma_inf: float | None = None
    c0: float | None = None
    p0: float | None = None
    table: tuple[tuple[float, float], ...] | None = None  # (pressure, overclosure)
    mu: float = 0.0
    stick_slope: float | str | None = None  # None: the default; CALCULIX: E/2
    tangent: str = "consistent"
    #: Newton iterations per increment in which slave nodes are re-paired (CalculiX: 8)
    pairing_iterations: int = 8
    method: str = "penalty"  # one of METHODS
    #: "augmented": the largest overclosure and stick slip left, per slave node spacing
    augmented_tolerance: float = 1e-4
    distribution: str | None = None  # one of DISTRIBUTIONS; None: default_distribution

    def __post_init__(self) -> None:
        validate(self, RULES)

    def resolved(self, E_slave: float, spacing: float | None = None) -> ContactSettings:
        """The defaults filled (:func:`defaults`)."""
        return replace(self, **defaults(self, E_slave, spacing))


RULES = Rules("contact", KEYS, (check_law,))
