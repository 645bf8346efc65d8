"""The analysis model shared by the scene reader and the Python API.

Plain dataclasses, no dolfinx.  Quantities whose default depends on the mesh
or on the slave body's material (``K``, ``sigma_inf``, ``stick_slope``) are
``None`` here (or :data:`CALCULIX` for CalculiX's rule) and resolved by
:meth:`ContactPair.resolved` once the slave body and its node spacing are known.

Every dataclass checks and converts its fields when built, by the rules of its scene-file
table (:data:`RULES`, with the checks of :mod:`dolfinx_friction.scene.validation`): a script and a
scene file are held to the same rules and get the same one-line :class:`SceneError`
messages (see :mod:`dolfinx_friction.scene.validation` for how the fields are named).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Optional, Union

from dolfinx_friction.fem import contact_settings, obstacles
from dolfinx_friction.fem.contact_settings import (  # noqa: F401  (re-exported)
    CALCULIX, LAWS, PENALTY_PER_SPACING, STICK_SLOPE_PER_SPACING, TANGENTS)
from dolfinx_friction.fem.obstacles import SHAPES  # noqa: F401  (re-exported)
from dolfinx_friction.nls.defaults import CHORD, CONVERGENCE, LINEAR_KINDS, STALL_ITERATIONS
from dolfinx_friction.rules import Key, Rules, validate
from dolfinx_friction.scene import validation as v

Vector = tuple[float, ...]
#: A prescribed displacement component, a number or ``None`` for "free".
Component = Optional[float]

#: Constitutive models of a body, small-strain linear elasticity or finite strain (the
#: scene is then solved geometrically nonlinearly): Saint Venant-Kirchhoff (Green-Lagrange
#: strain, second Piola-Kirchhoff stress from E and nu: CalculiX's NLGEOM with ``*ELASTIC``) and
#: compressible Neo-Hooke as CalculiX's ``*HYPERELASTIC, NEO HOOKE``.
MODELS = ("linear", "saint-venant-kirchhoff", "neo-hookean")



@dataclass(frozen=True)
class Body:
    """A deformable, isotropic elastic body: a physical group of cells."""

    name: str
    E: float
    nu: float
    degree: Optional[int] = None  # None: the geometry degree of the mesh
    #: 2D only: "strain" | "stress" (small strain only) | "axisymmetric" (a meridian
    #: section, r = x >= 0, z = y: values per full revolution)
    plane: str = "strain"
    thickness: float = 1.0  # 2D only, not axisymmetric
    model: str = "linear"  # one of MODELS

    def __post_init__(self) -> None:
        validate(self, RULES[Body])

    @property
    def finite_strain(self) -> bool:
        return self.model != "linear"

    @property
    def axisymmetric(self) -> bool:
        return self.plane == "axisymmetric"


@dataclass(frozen=True)
class Rigid:
    """An analytic rigid obstacle.

    plane: ``point``, ``normal``; sphere (circle in 2D): ``center``, ``radius``;
    cylinder (3D): ``point``, ``axis``, ``radius``.  The outward normal points
    towards the deformable body (for a sphere/cylinder: away from the axis).
    ``reference``: the point it rotates about (default: its ``point`` or ``center``).
    """

    name: str
    shape: str
    point: Optional[Vector] = None
    normal: Optional[Vector] = None
    center: Optional[Vector] = None
    axis: Optional[Vector] = None
    radius: Optional[float] = None
    reference: Optional[Vector] = None

    def __post_init__(self) -> None:
        validate(self, RULES[Rigid])


@dataclass(frozen=True)
class ContactPair:
    """Node-to-surface penalty contact between a slave facet group and a master.

    ``master`` names a facet group or a :class:`Rigid` obstacle.
    """

    slave: str
    master: str
    law: str = "linear"
    K: Union[float, str, None] = None  # None: the default; CALCULIX: 50 E
    sigma_inf: Optional[float] = None
    c0: Optional[float] = None
    p0: Optional[float] = None
    table: Optional[tuple[tuple[float, float], ...]] = None  # (pressure, overclosure)
    mu: float = 0.0
    stick_slope: Union[float, str, None] = None  # None: the default; CALCULIX: E/2
    tangent: str = "consistent"
    #: Newton iterations per increment in which slave nodes are re-paired;
    #: later iterations keep the pairing frozen (CalculiX: 8).
    pairing_iterations: int = 8
    #: "penalty" or "augmented" (Uzawa updates until the overclosure and the stick slip
    #: are below ``augmented_tolerance`` times the slave node spacing)
    method: str = "penalty"
    augmented_tolerance: float = 1e-4
    #: "nodal" or "mortar": how a slave node's force reaches a deformable master's nodes
    #: (the master face's shape functions at its projection, or mortar weights); None:
    #: "mortar" for quadratic slave faces on a deformable master, else "nodal"
    distribution: Optional[str] = None

    def __post_init__(self) -> None:
        validate(self, RULES[ContactPair])

    def resolved(self, E_slave: float, spacing: Optional[float] = None) -> "ContactPair":
        """Fill the defaults (docs/theory.md §8, scene-format.md version 2).

        ``sigma_inf = E/70000``, ``c0 = 1e-3``; with the slave node spacing ``h``
        (``spacing``, see :attr:`NodeToSurface.spacing`) also ``K = 10 E/h`` and
        ``stick_slope = E/h`` (:data:`PENALTY_PER_SPACING`, :data:`STICK_SLOPE_PER_SPACING`);
        :data:`CALCULIX` gives 50 E and E/2.  Without ``spacing`` a defaulted ``K`` and
        ``stick_slope`` stay ``None`` (the pressure laws other than linear need no ``h``).
        """
        return replace(self, **contact_settings.defaults(self, E_slave, spacing))


@dataclass(frozen=True)
class BC:
    """Prescribed displacement (totals at the end of the step) on a group."""

    on: str
    u: tuple[Component, ...]

    def __post_init__(self) -> None:
        validate(self, RULES[BC])


@dataclass(frozen=True)
class Load:
    """A traction vector or a normal pressure (positive pushes into the body) on a facet group."""

    on: str
    traction: Optional[Vector] = None
    pressure: Optional[float] = None

    def __post_init__(self) -> None:
        validate(self, RULES[Load])


@dataclass(frozen=True)
class RigidMotion:
    """Rigid obstacle driven by a total translation or a total force at the end of the step,
    and optionally turned to a total ``rotation`` about its reference point [rad]: an angle
    ``(theta,)`` in 2D (counter-clockwise), a rotation vector ``(tx, ty, tz)`` in 3D."""

    name: str
    displacement: Optional[Vector] = None
    force: Optional[Vector] = None
    rotation: Optional[Vector] = None

    def __post_init__(self) -> None:
        validate(self, RULES[RigidMotion])


@dataclass(frozen=True)
class Step:
    """A load step: the totals prescribed at its end, reached in ``increments`` equal
    increments (each halved at most ``max_cutbacks`` times), each solved by Newton."""

    name: str
    increments: int = 1
    max_cutbacks: int = 6
    newton_rtol: float = 1e-9
    newton_atol: float = 1e-10
    max_iterations: int = 30
    stall_iterations: int = STALL_ITERATIONS  # 0: never give up before max_iterations
    line_search: bool = True
    convergence: str = "residual"  # or "reactions": also stop once they no longer change
    reaction_tol: float = 1e-5
    bcs: tuple[BC, ...] = ()
    loads: tuple[Load, ...] = ()
    rigid: tuple[RigidMotion, ...] = ()

    def __post_init__(self) -> None:
        validate(self, RULES[Step])


@dataclass(frozen=True)
class Output:
    """What a run writes, and where (``dir`` None: ``<scene>_results`` next to the scene)."""

    dir: Optional[Path] = None
    reactions: Optional[tuple[str, ...]] = None  # None: every group carrying a bc
    fields: bool = True
    contact_table: bool = True

    def __post_init__(self) -> None:
        validate(self, RULES[Output])


@dataclass(frozen=True)
class SolverSettings:
    """The linear solver of the Newton iterations (``[solver]``): ``linear`` ``"direct"``
    (MUMPS), ``"iterative"`` (GMRES with algebraic multigrid) or ``"auto"`` (direct up to
    ``direct_max_dofs`` unknowns, default by dimension:
    :data:`~dolfinx_friction.nls.defaults.DIRECT_MAX_DOFS`); ``reuse_factorisation``
    (None: where it pays); ``petsc_options`` over the chosen solver's, as ``(name, value)``
    pairs (a dict is taken); ``chord``: a finite-strain Newton step solves with the last
    factorisation where the step before cut the residual to this share or less, whole and
    without a contact change (0: never; :data:`~dolfinx_friction.nls.defaults.CHORD`);
    ``solve_statuses``: a Newton step of linear bodies in frictionless contact solves for
    the contact statuses where that applies (:class:`~dolfinx_friction.Newton`)."""

    linear: str = "auto"
    direct_max_dofs: Optional[int] = None
    reuse_factorisation: Optional[bool] = None
    petsc_options: tuple[tuple[str, object], ...] = ()
    chord: float = CHORD
    solve_statuses: bool = True

    def __post_init__(self) -> None:
        validate(self, RULES[SolverSettings])


@dataclass(frozen=True)
class Scene:
    """A whole analysis: mesh, bodies, obstacles, contact pairs, steps, output."""

    mesh: Union[Path, object]  # a .msh path, or a live gmsh model (the ``gmsh`` module)
    bodies: tuple[Body, ...]
    steps: tuple[Step, ...]
    contacts: tuple[ContactPair, ...] = ()
    rigids: tuple[Rigid, ...] = ()
    output: Output = field(default_factory=Output)
    solver: SolverSettings = field(default_factory=SolverSettings)
    title: str = ""
    source: Optional[Path] = None  # the scene file, if read from one
    overrides: tuple[str, ...] = ()  # the ``--set KEY=VALUE`` applied to the file, as given

    def __post_init__(self) -> None:
        validate(self, RULES[Scene])

    def rigid(self, name: str) -> Optional[Rigid]:
        return next((r for r in self.rigids if r.name == name), None)

    def body(self, name: str) -> Optional[Body]:
        return next((b for b in self.bodies if b.name == name), None)

    def rotation_at(self, name: str, step: int, tau: float) -> Optional[tuple[float, ...]]:
        """The rotation of obstacle ``name`` at the time ``tau`` (0..1) of step ``step``
        [rad]: from the total at the end of the steps before (0 before any) to this step's
        total (the last one given), linearly; None if no step up to this one turns it."""
        def given(s: Step) -> Optional[tuple[float, ...]]:
            return next((m.rotation for m in s.rigid if m.name == name), None)
        start = None
        for s in self.steps[:step]:
            start = given(s) or start
        end = given(self.steps[step]) or start
        if end is None:
            return None
        start = start or (0.0,) * len(end)
        return tuple(a + tau * (b - a) for a, b in zip(start, end))


#: The rules of each dataclass, by scene-file key in file order: checked when an object is
#: built (from Python or by the scene reader, which takes the key names from here).
RULES: dict[type, Rules] = {
    Body: Rules("body", {
        "name": Key(v.name, required=True),
        "E": Key(v.modulus, required=True),
        "nu": Key(v.number(gt=-1, lt=0.5), required=True),
        "degree": Key(v.one_of(1, 2)),
        "plane": Key(v.one_of("strain", "stress", "axisymmetric")),
        "thickness": Key(v.number(gt=0)),
        "model": Key(v.one_of(*MODELS)),
    }, (v.check_body,)),
    Rigid: obstacles.RULES,
    ContactPair: Rules("contact", {
        "slave": Key(v.name, required=True),
        "master": Key(v.name, required=True),
        **contact_settings.KEYS,
    }, (contact_settings.check_law, v.check_not_self_contact)),
    BC: Rules("step.bc", {
        "on": Key(v.name, required=True),
        "u": Key(v.displacement, required=True),
    }),
    Load: Rules("step.load", {
        "on": Key(v.name, required=True),
        "traction": Key(v.vector()),
        "pressure": Key(v.ANY_NUMBER),
    }, (v.exactly_one("traction", "pressure"),)),
    RigidMotion: Rules("step.rigid", {
        "name": Key(v.name, required=True),
        "displacement": Key(v.vector()),
        "force": Key(v.vector()),
        "rotation": Key(v.rotation),
    }, (v.exactly_one("displacement", "force"),)),
    Step: Rules("step", {
        "name": Key(v.name),  # a scene file may leave it out: "step-<index>"
        "increments": Key(v.integer(1, 1_000_000)),
        "max_cutbacks": Key(v.integer(0, 50, "an increment halved more often is below the "
                                             "resolution of the pseudo-time")),
        "newton_rtol": Key(v.number(gt=0)),
        "newton_atol": Key(v.number(gt=0)),
        "max_iterations": Key(v.integer(1, 10_000)),
        "stall_iterations": Key(v.integer(0, 10_000)),
        "line_search": Key(v.boolean),
        "convergence": Key(v.one_of(*CONVERGENCE)),
        "reaction_tol": Key(v.number(gt=0, lt=1)),
        "bc": Key(v.items(BC), field="bcs"),
        "load": Key(v.items(Load), field="loads"),
        "rigid": Key(v.items(RigidMotion)),
    }, (v.check_step,)),
    Output: Rules("output", {
        "dir": Key(v.directory),
        "reactions": Key(v.names),
        "fields": Key(v.boolean),
        "contact_table": Key(v.boolean),
    }),
    SolverSettings: Rules("solver", {
        "linear": Key(v.one_of(*LINEAR_KINDS)),
        "direct_max_dofs": Key(v.integer(0, 10**12)),
        "reuse_factorisation": Key(v.boolean),
        "petsc_options": Key(v.petsc_options),
        "chord": Key(v.number(ge=0, lt=1)),
        "solve_statuses": Key(v.boolean),
    }),
    Scene: Rules("", {
        "title": Key(v.string),
        "mesh": Key(v.mesh_source, required=True),
        "body": Key(v.items(Body, min_length=1), required=True, field="bodies"),
        "rigid": Key(v.items(Rigid), field="rigids"),
        "contact": Key(v.items(ContactPair), field="contacts"),
        "step": Key(v.items(Step, min_length=1), required=True, field="steps"),
        "output": Key(v.instance(Output)),
        "solver": Key(v.instance(SolverSettings)),
    }, (v.check_scene,)),
}
