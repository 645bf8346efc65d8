"""Analytic rigid obstacles, the master of a :class:`~dolfinx_friction.NodeToSurface`.

An :class:`Obstacle` is a shape and its geometry, no dolfinx: plane (``point``,
``normal``), sphere (a circle in 2D: ``center``, ``radius``) or cylinder (3D: ``point``,
``axis``, ``radius``).  The outward normal points towards the deformable body (for a
sphere or a cylinder: away from the axis).  :func:`rigid_plane`, :func:`rigid_sphere` and
:func:`rigid_cylinder` check what they are given (:class:`~dolfinx_friction.errors.
ContactSetupError`) and make unit directions; the scene builds its ``[[rigid]]`` obstacles
as they are (:meth:`Obstacle.like`).

An obstacle moves rigidly: its current geometry is its reference shape rotated by ``Q``
about its ``reference`` point ``c`` (default: the shape's ``point`` or ``center``), then
translated by ``t``: ``x = Q (X - c) + c + t`` (:func:`rotation_matrix`, :meth:`Obstacle.moved`).
On the Python API an obstacle can also be given by a signed distance function
(:func:`rigid_sdf`, :class:`SignedDistance`), its gradient the normal.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from dolfinx_friction import rules as r
from dolfinx_friction.errors import ContactSetupError
from dolfinx_friction.rules import Key, Rules, fail, join, validate

__all__ = ["SHAPES", "Obstacle", "SignedDistance", "rigid_cylinder", "rigid_plane",
           "rigid_sdf", "rigid_sphere", "rotation_matrix", "rotation_size"]

SHAPES = ("plane", "sphere", "cylinder")
Vector = tuple[float, ...]


@dataclass(frozen=True)
class Obstacle:
    """An analytic rigid obstacle in its reference position (its translation and rotation
    are the contact's, :attr:`~dolfinx_friction.NodeToSurface.obstacle_translation` and
    :attr:`~dolfinx_friction.NodeToSurface.obstacle_rotation`); ``reference`` is the point
    it rotates about (default: :attr:`pivot`)."""

    name: str
    shape: str  # one of SHAPES
    point: Vector | None = None
    normal: Vector | None = None
    center: Vector | None = None
    axis: Vector | None = None
    radius: float | None = None
    reference: Vector | None = None

    def __post_init__(self) -> None:
        validate(self, RULES)

    @classmethod
    def like(cls, rigid: Any) -> Obstacle:
        """The obstacle of any object with the same attributes (a scene ``Rigid``)."""
        return cls(rigid.name, rigid.shape, point=rigid.point, normal=rigid.normal,
                   center=rigid.center, axis=rigid.axis, radius=rigid.radius,
                   reference=rigid.reference)

    @property
    def pivot(self) -> Vector:
        """The point the obstacle rotates about: ``reference``, else the shape's ``point``
        (plane, cylinder) or ``center`` (sphere)."""
        if self.reference is not None:
            return self.reference
        return self.center if self.shape == "sphere" else self.point

    def moved(self, Q) -> dict:
        """The shape's parameters rotated by ``Q`` (gdim, gdim) about :attr:`pivot` (the
        translation is applied by the element): ``point``, ``normal``, ``center``, ``axis``,
        ``radius`` as :func:`~dolfinx_friction.contact.element.rigid_kinematics` takes them."""
        import numpy as np
        c = np.asarray(self.pivot, float)
        out: dict = {"radius": self.radius or 0.0}
        for key in ("point", "center"):
            v = getattr(self, key)
            out[key] = None if v is None else Q @ (np.asarray(v, float) - c) + c
        for key in ("normal", "axis"):
            v = getattr(self, key)
            out[key] = None if v is None else Q @ np.asarray(v, float)
        return out


@dataclass(frozen=True)
class SignedDistance:
    """A rigid obstacle given by a signed distance function (Python API only): ``distance(y)``
    (n, gdim) -> (n,) [length], > 0 outside the obstacle (towards the body), and its
    ``gradient(y)`` (n, gdim), the outward normal; ``hessian(y)`` (n, gdim, gdim) makes the
    tangent exact (:func:`rigid_sdf` defaults it to central differences of the gradient).
    ``y`` are points of the obstacle's reference frame; it turns about ``reference`` (none:
    it cannot turn, and its moment is taken about the origin)."""

    distance: Callable[[Any], Any]
    gradient: Callable[[Any], Any]
    hessian: Callable[[Any], Any]
    reference: Vector | None = None
    name: str = "sdf"
    shape: str = "sdf"

    @property
    def pivot(self) -> Vector | None:
        """The point it rotates about, ``reference`` (None: it cannot rotate)."""
        return self.reference


def rigid_sdf(distance: Callable[[Any], Any], gradient: Callable[[Any], Any],
              hessian: Callable[[Any], Any] | None = None,
              reference: Sequence[float] | None = None, name: str = "sdf",
              step: float = 1e-6) -> SignedDistance:
    """A rigid obstacle given by a signed distance (:class:`SignedDistance`); without
    ``hessian``, central differences of ``gradient`` with ``step`` [length] (the tangent is
    then exact to about ``step**2`` times the third derivatives)."""
    if not (callable(distance) and callable(gradient)
            and (hessian is None or callable(hessian))):
        raise ContactSetupError(f"{name}: distance, gradient and hessian must be callables")
    if hessian is None:
        import numpy as np

        def hessian(y):
            y = np.asarray(y, float)
            d = y.shape[1]
            columns = [(np.asarray(gradient(y + step * e), float)
                        - np.asarray(gradient(y - step * e), float)) / (2 * step)
                       for e in np.eye(d)]
            return np.stack(columns, axis=2)
    return SignedDistance(distance, gradient, hessian, _reference(reference, name), name)


def rotation_size(gdim: int) -> int:
    """Components of a rotation: 1 in 2D (an angle), 3 in 3D (a rotation vector)."""
    return 1 if gdim == 2 else 3


def rotation_matrix(rotation, gdim: int):
    """(gdim, gdim) rotation matrix of ``rotation`` [rad]: in 2D an angle (a number or one
    component), counter-clockwise; in 3D a rotation vector (axis times angle, Rodrigues)."""
    import numpy as np
    theta = np.atleast_1d(np.asarray(rotation, dtype=float))
    if gdim == 2:
        c, s = np.cos(theta[0]), np.sin(theta[0])
        return np.array([[c, -s], [s, c]])
    angle = float(np.linalg.norm(theta))
    if angle == 0.0:
        return np.eye(3)
    k = theta / angle
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)


def _vector(values, what: str) -> tuple[float, ...]:
    import numpy as np  # (here: reading a scene imports this module, not numpy)
    v = tuple(float(c) for c in values)
    if not all(np.isfinite(v)):
        raise ContactSetupError(f"{what} must be finite, got {v}")
    return v


def _direction(values, what: str) -> tuple[float, ...]:
    """A unit vector along ``values`` (scaled first: 1e-200 components are a direction)."""
    import numpy as np
    v = np.asarray(_vector(values, what))
    scale = np.abs(v).max(initial=0.0)
    if scale == 0.0:
        raise ContactSetupError(f"{what} is zero: a rigid obstacle needs a direction")
    v = v / scale
    return tuple(float(c) for c in v / np.linalg.norm(v))


def _reference(reference: Sequence[float] | None, what: str) -> tuple[float, ...] | None:
    return None if reference is None else _vector(reference, f"{what} reference")


def rigid_plane(point: Sequence[float], normal: Sequence[float],
                name: str = "plane", reference: Sequence[float] | None = None) -> Obstacle:
    """A rigid plane through ``point``; ``normal`` points towards the deformable body;
    it rotates about ``reference`` (default: ``point``)."""
    return Obstacle(name, "plane", point=_vector(point, "rigid plane point"),
                    normal=_direction(normal, "rigid plane normal"),
                    reference=_reference(reference, "rigid plane"))


def rigid_sphere(center: Sequence[float], radius: float, name: str = "sphere",
                 reference: Sequence[float] | None = None) -> Obstacle:
    """A rigid sphere (a circle in 2D); the body touches it from outside; it rotates about
    ``reference`` (default: ``center``)."""
    if not float(radius) > 0.0:
        raise ContactSetupError(f"rigid sphere radius must be positive, got {radius}")
    return Obstacle(name, "sphere", center=_vector(center, "rigid sphere center"),
                    radius=float(radius), reference=_reference(reference, "rigid sphere"))


def rigid_cylinder(point: Sequence[float], axis: Sequence[float], radius: float,
                   name: str = "cylinder", reference: Sequence[float] | None = None
                   ) -> Obstacle:
    """A rigid circular cylinder (3D) through ``point`` along ``axis``; it rotates about
    ``reference`` (default: ``point``)."""
    if not float(radius) > 0.0:
        raise ContactSetupError(f"rigid cylinder radius must be positive, got {radius}")
    return Obstacle(name, "cylinder", point=_vector(point, "rigid cylinder point"),
                    axis=_direction(axis, "rigid cylinder axis"), radius=float(radius),
                    reference=_reference(reference, "rigid cylinder"))


SHAPE_KEYS = {"plane": ("point", "normal"), "sphere": ("center", "radius"),
              "cylinder": ("point", "axis", "radius")}
_GEOMETRY_KEYS = ("point", "normal", "center", "axis", "radius")


def check_shape(rigid: Any, key: str) -> None:
    needed = SHAPE_KEYS[rigid.shape]
    for name_ in _GEOMETRY_KEYS:
        given = getattr(rigid, name_) is not None
        if name_ in needed and not given:
            fail(join(key, name_), f"required for shape {rigid.shape!r}")
        if name_ not in needed and given:
            fail(join(key, name_), f"not a parameter of shape {rigid.shape!r} "
                 f"(it takes {', '.join(needed)})", getattr(rigid, name_))


#: The rules of an obstacle, by scene-file key in file order (the scene's ``[[rigid]]``
#: has the same: a script and a scene file get the same messages).
KEYS: dict[str, Key] = {
    "name": Key(r.name, required=True),
    "shape": Key(r.one_of(*SHAPES), required=True),
    "point": Key(r.vector()),
    "normal": Key(r.vector(nonzero=True)),
    "center": Key(r.vector()),
    "axis": Key(r.vector(nonzero=True)),
    "radius": Key(r.number(gt=0)),
    "reference": Key(r.vector()),
}
RULES = Rules("rigid", KEYS, (check_shape,))
