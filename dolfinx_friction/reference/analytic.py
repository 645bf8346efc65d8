"""Closed-form reference solutions for the demos and tests.

All functions are plain numpy (no dolfinx) and work in any consistent unit
system.  References:

* K. L. Johnson, *Contact Mechanics*, Cambridge University Press (1985):
  Hertz contact of cylinders (§4.3) and spheres (§4.2), tangential loading of
  cylinders and spheres in partial slip (Cattaneo–Mindlin, §7.1–§7.2).
* S. P. Timoshenko, J. N. Goodier, *Theory of Elasticity*, 3rd ed. (1970), §33: thick
  cylinders under pressure (Lamé), shrink fits.
* Statics of a block on a rough inclined plane (Beer & Johnston, Meriam &
  Kraige, ...): the horizontal force that pushes a block of weight ``W`` up a
  slope at impending/steady sliding is ``P = W (sin a + mu cos a)/(cos a - mu sin a)``.

Run ``python -m dolfinx_friction.reference.analytic`` for the self-checks (they compare
against the textbook numbers quoted in the docstrings and against
independent forms of the same results).

Effective quantities (Johnson §4.2)::

    1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2      (a rigid body has 1/E = 0)
    1/R  = 1/R1 + 1/R2                          (a plane has 1/R = 0)
"""
from __future__ import annotations

import logging
import math
from typing import NamedTuple, Optional

import numpy as np

__all__ = [
    "effective_modulus", "effective_radius",
    "HertzLine", "hertz_line", "hertz_line_load", "hertz_line_pressure",
    "HertzSphere", "hertz_sphere", "hertz_sphere_force", "hertz_sphere_pressure",
    "cattaneo_mindlin_stick_half_width", "cattaneo_mindlin_traction",
    "mindlin_sphere_stick_radius",
    "lame_cylinder_displacement", "shrink_fit_pressure",
    "incline_push_ratio", "incline_hold_ratio",
    "fit_elliptic", "self_check",
]

logger = logging.getLogger(__name__)


# ------------------------------------------------------------------ effective
def effective_modulus(E1: float, nu1: float, E2: Optional[float] = None,
                      nu2: float = 0.0) -> float:
    """Contact modulus ``E*`` with ``1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2``.

    ``E2=None`` (or ``inf``) makes the second body rigid.

    >>> round(effective_modulus(1000.0, 0.3), 4)          # elastic on rigid
    1098.9011
    >>> round(effective_modulus(200e3, 0.3, 200e3, 0.3))  # steel on steel [MPa]
    109890
    """
    c = (1.0 - nu1 ** 2) / E1
    if E2 is not None and math.isfinite(E2):
        c += (1.0 - nu2 ** 2) / E2
    return 1.0 / c


def effective_radius(R1: float, R2: Optional[float] = None) -> float:
    """``R`` with ``1/R = 1/R1 + 1/R2``; ``R2=None``/``inf`` is a plane (negative = concave)."""
    if R2 is None or not math.isfinite(R2):
        return R1
    return 1.0 / (1.0 / R1 + 1.0 / R2)


# ------------------------------------------------------------- line contact
class HertzLine(NamedTuple):
    """Hertz line contact (plane strain): half-width ``a`` and peak pressure ``p0``."""

    a: float
    p0: float


def hertz_line(P: float, R: float, E_star: float) -> HertzLine:
    """Cylinder (radius ``R``) on a half-space, load ``P`` per unit length (plane strain).

    ``a = sqrt(4 P R / (pi E*))`` and ``p0 = 2 P / (pi a) = sqrt(P E* / (pi R))``
    (Johnson §4.3).  The pressure is elliptic, see :func:`hertz_line_pressure`.

    Example: a steel roller ``R = 10 mm`` on a steel flat (``E = 200 GPa``,
    ``nu = 0.3``, ``E* = 109.9 GPa``) under ``P = 100 N/mm``:

    >>> h = hertz_line(100.0, 10.0, effective_modulus(200e3, 0.3, 200e3, 0.3))
    >>> round(h.a, 4), round(h.p0, 1)
    (0.1076, 591.4)

    (Cross-checked in :func:`self_check` against the handbook form for two
    rollers of one material, contact width ``2a = sqrt(32 P (1-nu^2) r / (pi E))``.)
    """
    a = math.sqrt(4.0 * P * R / (math.pi * E_star))
    return HertzLine(a, 2.0 * P / (math.pi * a))


def hertz_line_load(a: float, R: float, E_star: float) -> float:
    """Load per unit length that gives the contact half-width ``a``: ``P = pi E* a^2 / (4 R)``."""
    return math.pi * E_star * a * a / (4.0 * R)


def hertz_line_pressure(x, P: float, R: float, E_star: float) -> np.ndarray:
    """Pressure ``p(x) = p0 sqrt(1 - x^2/a^2)`` for ``|x| < a``, 0 outside (``x``: from the
    centre)."""
    a, p0 = hertz_line(P, R, E_star)
    x = np.asarray(x, dtype=float)
    return p0 * np.sqrt(np.clip(1.0 - (x / a) ** 2, 0.0, None))


# ------------------------------------------------------------------ spheres
class HertzSphere(NamedTuple):
    """Hertz point contact: contact radius ``a``, peak pressure ``p0``, approach ``delta``."""

    a: float
    p0: float
    delta: float


def hertz_sphere(F: float, R: float, E_star: float) -> HertzSphere:
    """Sphere (radius ``R``) on a half-space under the force ``F`` (Johnson §4.2).

    ``a = (3 F R / (4 E*))^(1/3)``, ``p0 = 3 F / (2 pi a^2)``, ``delta = a^2 / R``
    (``delta`` is the approach of distant points of the two bodies).

    Textbook number: a sphere ``R = 8 mm`` pressed on a rigid flat by
    ``F = 60 pi N`` (``E = 1000 N/mm^2``, ``nu = 0.3``) has ``a = 1.010 mm``
    (a standard finite-element exercise that compares an axisymmetric model with
    this value):

    >>> round(hertz_sphere(60 * math.pi, 8.0, effective_modulus(1000.0, 0.3)).a, 3)
    1.01
    """
    a = (3.0 * F * R / (4.0 * E_star)) ** (1.0 / 3.0)
    return HertzSphere(a, 3.0 * F / (2.0 * math.pi * a * a), a * a / R)


def hertz_sphere_force(delta: float, R: float, E_star: float) -> float:
    """Force for a given approach: ``F = (4/3) E* sqrt(R) delta^(3/2)``."""
    return 4.0 / 3.0 * E_star * math.sqrt(R) * delta ** 1.5


def hertz_sphere_pressure(r, F: float, R: float, E_star: float) -> np.ndarray:
    """Pressure ``p(r) = p0 sqrt(1 - r^2/a^2)`` for ``r < a``, 0 outside (``r`` from the axis)."""
    a, p0, _ = hertz_sphere(F, R, E_star)
    r = np.asarray(r, dtype=float)
    return p0 * np.sqrt(np.clip(1.0 - (r / a) ** 2, 0.0, None))


# --------------------------------------------------------- shrink fit (Lamé)
def lame_cylinder_displacement(r, r_a: float, r_b: float, p_a: float, p_b: float, E: float,
                               nu: float, ends: str = "free") -> np.ndarray:
    """Radial displacement ``u(r)`` of a thick cylinder ``r_a <= r <= r_b`` under the
    pressures ``p_a`` inside and ``p_b`` outside (Lamé; Timoshenko & Goodier §33).

    ``sigma_r = A - B/r^2``, ``sigma_theta = A + B/r^2`` with
    ``A = (p_a r_a^2 - p_b r_b^2) / (r_b^2 - r_a^2)``,
    ``B = (p_a - p_b) r_a^2 r_b^2 / (r_b^2 - r_a^2)``; ``ends = "free"``: ``sigma_z = 0``,
    ``u = ((1 - nu) A r + (1 + nu) B / r) / E``; ``"held"`` (plane strain, ``eps_z = 0``):
    ``u = (1 + nu) ((1 - 2 nu) A r + B / r) / E``.
    """
    r = np.asarray(r, dtype=float)
    A = (p_a * r_a ** 2 - p_b * r_b ** 2) / (r_b ** 2 - r_a ** 2)
    B = (p_a - p_b) * r_a ** 2 * r_b ** 2 / (r_b ** 2 - r_a ** 2)
    if ends == "free":
        return ((1.0 - nu) * A * r + (1.0 + nu) * B / r) / E
    if ends == "held":
        return (1.0 + nu) * ((1.0 - 2.0 * nu) * A * r + B / r) / E
    raise ValueError(f"ends must be 'free' or 'held', not {ends!r}")


def shrink_fit_pressure(delta: float, r_i: float, r_c: float, r_o: float, E: float,
                        nu: float = 0.0, ends: str = "free") -> float:
    """Contact pressure of a shrink fit of two thick cylinders of one material (Lamé): an
    inner one ``r_i .. r_c + delta`` in an outer one ``r_c .. r_o``, radial interference
    ``delta << r_c``, frictionless::

        p = E' delta (r_o^2 - r_c^2) (r_c^2 - r_i^2) / (2 r_c^3 (r_o^2 - r_i^2))

    with ``E' = E`` for free ends (``sigma_z = 0``, ``nu`` drops out) and
    ``E' = E / (1 - nu^2)`` for ends held axially (plane strain, ``eps_z = 0``): the
    interference is taken up by the outer cylinder's widening and the inner one's
    shrinking at ``r_c``, :func:`lame_cylinder_displacement`.
    """
    if ends not in ("free", "held"):
        raise ValueError(f"ends must be 'free' or 'held', not {ends!r}")
    E_eff = E if ends == "free" else E / (1.0 - nu * nu)
    return (E_eff * delta * (r_o ** 2 - r_c ** 2) * (r_c ** 2 - r_i ** 2)
            / (2.0 * r_c ** 3 * (r_o ** 2 - r_i ** 2)))


# --------------------------------------------------------- partial slip
def cattaneo_mindlin_stick_half_width(a: float, Q: float, mu: float, P: float) -> float:
    """Stick half-width of a cylinder under ``P`` then a tangential ``Q < mu P`` (2D).

    ``c = a sqrt(1 - Q / (mu P))`` (Johnson §7.1): the stick zone ``|x| < c`` is
    centred in the Hertz contact ``|x| < a``; slip occurs in ``c < |x| < a``.
    Valid for elastically similar bodies (no coupling between normal and
    tangential tractions) and monotonic ``Q`` at constant ``P``.
    For a sphere the exponent is 1/3, see :func:`mindlin_sphere_stick_radius`.

    >>> cattaneo_mindlin_stick_half_width(1.0, 0.75, 0.5, 2.0)   # Q/(mu P) = 3/4
    0.5
    """
    ratio = Q / (mu * P)
    if not 0.0 <= ratio <= 1.0:
        raise ValueError(f"Q/(mu P) = {ratio:g} must lie in [0, 1]")
    return a * math.sqrt(1.0 - ratio)


def cattaneo_mindlin_traction(x, a: float, c: float, mu: float, p0: float) -> np.ndarray:
    """Tangential traction of the cylinder in partial slip (Johnson §7.1).

    ``q(x) = mu p0 sqrt(1 - x^2/a^2) - mu p0 (c/a) sqrt(1 - x^2/c^2)``, the second
    term only in the stick zone ``|x| < c``.  It integrates to
    ``Q = mu P (1 - c^2/a^2)``.
    """
    x = np.asarray(x, dtype=float)
    q = mu * p0 * np.sqrt(np.clip(1.0 - (x / a) ** 2, 0.0, None))
    if c > 0.0:
        q = q - mu * p0 * (c / a) * np.sqrt(np.clip(1.0 - (x / c) ** 2, 0.0, None))
    return q


def mindlin_sphere_stick_radius(a: float, Q: float, mu: float, P: float) -> float:
    """Stick radius of a sphere in partial slip: ``c = a (1 - Q/(mu P))^(1/3)`` (Johnson §7.2)."""
    ratio = Q / (mu * P)
    if not 0.0 <= ratio <= 1.0:
        raise ValueError(f"Q/(mu P) = {ratio:g} must lie in [0, 1]")
    return a * (1.0 - ratio) ** (1.0 / 3.0)


# ------------------------------------------------------------------ incline
def carter_saturation_creep(mu: float, a: float, R: float) -> float:
    """Creep at which a rolling cylinder slips over its whole contact: ``xi_sat = mu a / R``
    (Carter 1926; Johnson §8.3), ``a`` the Hertz half-width (:func:`hertz_line`)."""
    return mu * a / R


def carter_creep_force(creep: float, mu: float, a: float, R: float) -> float:
    """Tangential force over ``mu P`` of a cylinder rolling with ``creep`` (the relative
    velocity of slip over the rolling velocity) on a half-space, plane strain:
    ``1 - (1 - xi/xi_sat)^2`` below :func:`carter_saturation_creep`, 1 above (signed as the
    creep).

    The stick zone is the leading ``2c`` of the contact, ``c/a = 1 - xi/xi_sat``, its traction
    Carter's ``mu p0 (sqrt(1 - x^2/a^2) - (c/a) sqrt(1 - (x - a + c)^2/c^2))``
    (:func:`carter_traction`), which strains the surface uniformly by
    ``2 mu p0 (a - c) / (E* a) = xi`` in the stick zone.  It holds where normal pressure moves
    no surface point tangentially (uncoupled: Dundurs' beta = 0): two bodies of one material,
    or a rigid cylinder on an incompressible half-space (``1/E* = (1 - nu^2)/E``).

    >>> round(carter_creep_force(0.5 * 0.3 * 0.04, 0.3, 0.04, 1.0), 4)
    0.75
    """
    ratio = abs(creep) / carter_saturation_creep(mu, a, R)
    return math.copysign(1.0 - (1.0 - min(ratio, 1.0)) ** 2, creep)


def carter_traction(x, a: float, c: float, mu: float, p0: float) -> np.ndarray:
    """Carter's tangential traction at ``x`` (rolling towards +x): the Hertz traction
    ``mu p0 sqrt(1 - x^2/a^2)`` less a stick-zone correction of half-width ``c`` centred at
    ``a - c`` (the leading edge)."""
    x = np.asarray(x, dtype=float)
    full = mu * p0 * np.sqrt(np.clip(1.0 - (x / a) ** 2, 0.0, None))
    if c <= 0.0:
        return full
    s = (x - (a - c)) / c
    return full - mu * p0 * (c / a) * np.sqrt(np.clip(1.0 - s ** 2, 0.0, None))


def incline_push_ratio(tan_alpha: float, mu: float) -> float:
    """``H/V = (tan a + mu) / (1 - mu tan a)`` for a block sliding *up* a rough slope.

    Exact loading for which it holds: a rigid plane inclined by ``a`` (rising
    in the push direction), a block resting on it under a **vertical** force
    ``V`` (its weight, or a vertical dead load) and pushed by a **horizontal**
    force ``H``; the block slides (or is on the point of sliding) up the
    slope, so every contact point slips in the up-slope direction and the
    Coulomb law gives a friction force ``mu N`` pointing down the slope.
    Equilibrium of the resultants in the horizontal and vertical directions,
    ``H = N sin a + mu N cos a`` and ``V = N cos a - mu N sin a``, gives the
    ratio, independently of how the pressure is distributed over the contact
    (moments do not enter).  It requires ``mu tan a < 1`` (otherwise no
    horizontal push can move the block up).  Under stick (partial slip) the
    ratio is smaller.

    Textbook form: ``P = W (sin a + mu cos a) / (cos a - mu sin a)``.

    >>> round(incline_push_ratio(0.1, 0.3), 6)
    0.412371
    """
    if mu * tan_alpha >= 1.0:
        raise ValueError("mu tan(alpha) >= 1: the block cannot be pushed up by a horizontal force")
    return (tan_alpha + mu) / (1.0 - mu * tan_alpha)


def incline_hold_ratio(tan_alpha: float, mu: float) -> float:
    """``H/V = (tan a - mu) / (1 + mu tan a)``: the horizontal force at which the block starts
    to slide *down* the slope (negative: it must be pulled; 0 or below = self-locking)."""
    return (tan_alpha - mu) / (1.0 + mu * tan_alpha)


# ------------------------------------------------------------------ fitting
def fit_elliptic(x: np.ndarray, p: np.ndarray, floor: float = 0.2) -> tuple[float, float]:
    """``(a, p0)`` of the Hertz profile ``p^2 = p0^2 (1 - x^2/a^2)`` fitted by least squares
    to nodal pressures ``p`` at distances ``x`` from the centre (nodes with p > floor max p).

    Exact for exact Hertz data:

    >>> x = np.linspace(0.0, 0.9, 10)
    >>> [round(v, 12) for v in fit_elliptic(x, 3.0 * np.sqrt(1.0 - (x / 1.5) ** 2))]
    [1.5, 3.0]
    """
    x, p = np.asarray(x, float), np.asarray(p, float)
    keep = p > floor * p.max()
    A = np.column_stack([np.ones(keep.sum()), x[keep] ** 2])
    c0, c1 = np.linalg.lstsq(A, p[keep] ** 2, rcond=None)[0]
    return float(np.sqrt(-c0 / c1)), float(np.sqrt(c0))


# --------------------------------------------------------------- self-check
_trapezoid = getattr(np, "trapezoid", None) or np.trapz  # numpy 2 renamed trapz


def self_check() -> None:
    """Check every formula against a textbook number or an independent form; raises on failure.

    Each check is logged (logger ``dolfinx_friction.reference.analytic``, level INFO)."""
    checks = []

    def close(name, got, want, rtol=1e-9):
        ok = abs(got - want) <= rtol * abs(want)
        checks.append((name, got, want, ok))

    # Hertz sphere: textbook exercise R = 8 mm, F = 60 pi N, E = 1000, nu = 0.3 -> a = 1.010 mm
    s = hertz_sphere(60 * math.pi, 8.0, effective_modulus(1000.0, 0.3))
    close("sphere a (textbook 1.010 mm)", round(s.a, 3), 1.010)
    # the force integrates the pressure; F(delta) inverts delta(F)
    r = np.linspace(0.0, s.a, 200001)
    F = _trapezoid(2 * np.pi * r * hertz_sphere_pressure(r, 60 * math.pi, 8.0,
                                                       effective_modulus(1000.0, 0.3)), r)
    close("sphere: integral of p = F", F, 60 * math.pi, 1e-5)
    close("sphere: F(delta(F)) = F",
          hertz_sphere_force(s.delta, 8.0, effective_modulus(1000.0, 0.3)), 60 * math.pi)
    # two identical spheres with imposed crush h (code_aster benchmark v6.04.222 form):
    # p0 = E/(pi (1-nu^2)) sqrt(2h/R), a = sqrt(R h / 2)
    E, nu, Rs, h = 200e3, 0.3, 50.0, 4.0
    Es, Re = effective_modulus(E, nu, E, nu), effective_radius(Rs, Rs)
    sh = hertz_sphere(hertz_sphere_force(h, Re, Es), Re, Es)
    close("two spheres: a = sqrt(R h/2)", sh.a, math.sqrt(Rs * h / 2))
    close("two spheres: p0 = E/(pi(1-nu^2)) sqrt(2h/R)", sh.p0,
          E / (math.pi * (1 - nu ** 2)) * math.sqrt(2 * h / Rs))

    # shrink fit: the pressure closes the interference between the Lamé displacements
    # of the two cylinders at r_c (both end conditions)
    r_i, r_c, r_o, dl = 1.0, 2.0, 3.0, 0.01
    for ends in ("free", "held"):
        p = shrink_fit_pressure(dl, r_i, r_c, r_o, E, nu, ends)
        gap = (lame_cylinder_displacement(r_c, r_c, r_o, p, 0.0, E, nu, ends)
               - lame_cylinder_displacement(r_c, r_i, r_c, 0.0, p, E, nu, ends))
        close(f"shrink fit ({ends} ends): u_outer - u_inner = delta", gap, dl)
    # a thin ring (relative thickness t) on a solid shaft takes up the interference alone:
    # its hoop stress p / t widens it by p r_c / (t E), so p -> E delta t / r_c as t -> 0
    t = 1e-6
    close("shrink fit: thin ring on a shaft, p = E delta t / r_c",
          shrink_fit_pressure(dl, 0.0, r_c, r_c * (1 + t), E), E * dl * t / r_c, 1e-5)

    # Hertz line: handbook form for two rollers of one material:
    # width 2a = sqrt(32 P (1-nu^2) / (pi E (1/r1 + 1/r2))), peak 4P/(pi 2a)
    P, r1, r2 = 100.0, 10.0, 25.0
    Es = effective_modulus(E, nu, E, nu)
    hl = hertz_line(P, effective_radius(r1, r2), Es)
    w = math.sqrt(32 * P * (1 - nu ** 2) / (math.pi * E * (1 / r1 + 1 / r2)))
    close("line: 2a = handbook width", 2 * hl.a, w)
    close("line: p0 = 4P/(pi w)", hl.p0, 4 * P / (math.pi * w))
    close("line: p0 = sqrt(P E*/(pi R))", hl.p0,
          math.sqrt(P * Es / (math.pi * effective_radius(r1, r2))))
    x = np.linspace(-hl.a, hl.a, 400001)
    close("line: integral of p = P",
          _trapezoid(hertz_line_pressure(x, P, effective_radius(r1, r2), Es), x), P, 1e-5)
    close("line: load for half-width", hertz_line_load(hl.a, effective_radius(r1, r2), Es), P)

    # Cattaneo-Mindlin (cylinder): q integrates to Q = mu P (1 - c^2/a^2)
    mu, Q = 0.3, 0.6 * 0.3 * P
    c = cattaneo_mindlin_stick_half_width(hl.a, Q, mu, P)
    close("CM: c/a = sqrt(1 - Q/(mu P)) = sqrt(0.4)", c / hl.a, math.sqrt(0.4))
    close("CM: integral of q = Q",
          _trapezoid(cattaneo_mindlin_traction(x, hl.a, c, mu, hl.p0), x), Q, 1e-4)
    close("Mindlin sphere: c/a = (1 - 7/8)^(1/3) = 1/2",
          mindlin_sphere_stick_radius(1.0, 0.4375, 0.5, 1.0), 0.5)

    # Carter: the traction integrates to mu P (1 - c^2/a^2) = the creep-force law at the
    # creep whose stick zone is c; its surface strain in the stick zone (the Hilbert
    # transform of q, 1/pi PV int q(s)/(x - s) ds = mu p0 (a - c)/a there) is the creep
    c = 0.4 * hl.a
    creep = 2 * mu * hl.p0 * (hl.a - c) / (Es * hl.a)
    close("Carter: creep at c/a = 0.4 is 0.6 xi_sat", creep,
          0.6 * carter_saturation_creep(mu, hl.a, effective_radius(r1, r2)))
    close("Carter: integral of q = mu P (1 - c^2/a^2)",
          _trapezoid(carter_traction(x, hl.a, c, mu, hl.p0), x), mu * P * (1 - 0.16), 1e-4)
    close("Carter: creep-force law at c/a = 0.4",
          carter_creep_force(creep, mu, hl.a, effective_radius(r1, r2)), 1 - 0.16)
    s_ = np.linspace(-hl.a, hl.a, 2_000_001)
    q = carter_traction(s_, hl.a, c, mu, hl.p0)
    for xi in np.linspace(hl.a - 1.9 * c, hl.a - 0.1 * c, 4):  # inside the stick zone
        # PV int q/(x - s) = int (q(s) - q(x))/(x - s) + q(x) ln((a + x)/(a - x))
        qx = carter_traction(xi, hl.a, c, mu, hl.p0)
        gap = np.where(s_ != xi, xi - s_, 1.0)
        pv = (_trapezoid((q - qx) / gap, s_) + qx * math.log((hl.a + xi) / (hl.a - xi)))
        close(f"Carter: stick-zone strain at x/a = {xi / hl.a:.2f}", pv / math.pi,
              mu * hl.p0 * (hl.a - c) / hl.a, 1e-3)

    # incline: solve the equilibrium of a block on the slope numerically
    tan_a, mu = 0.1, 0.3
    al = math.atan(tan_a)
    n = np.array([-math.sin(al), math.cos(al)])  # plane normal (towards the block)
    t = np.array([math.cos(al), math.sin(al)])  # up-slope direction
    V = 1.0
    # unknowns N, H: N n - mu N t + (H, -V) = 0
    A = np.array([[n[0] - mu * t[0], 1.0], [n[1] - mu * t[1], 0.0]])
    N, H = np.linalg.solve(A, [0.0, V])
    close("incline: H/V from equilibrium", H / V, incline_push_ratio(tan_a, mu))
    close("incline: textbook (sin a + mu cos a)/(cos a - mu sin a)",
          incline_push_ratio(tan_a, mu),
          (math.sin(al) + mu * math.cos(al)) / (math.cos(al) - mu * math.sin(al)))
    close("incline: hold ratio with mu = 0 is tan a", incline_hold_ratio(tan_a, 0.0), tan_a)

    failed = [c for c in checks if not c[3]]
    for name, got, want, ok in checks:
        logger.info("%s %s: %.10g (expected %.10g)", "ok  " if ok else "FAIL", name, got, want)
    if failed:
        raise AssertionError(f"{len(failed)} analytic self-checks failed: "
                             f"{[c[0] for c in failed]}")


if __name__ == "__main__":
    import doctest

    logging.basicConfig(level=logging.INFO, format="%(message)s")
    self_check()
    failures, tests = doctest.testmod()
    print(f"doctest: {tests - failures}/{tests} passed")
    raise SystemExit(1 if failures else 0)
