"""Pressure-overclosure laws (docs/theory.md §4.1, §4.2).

Each law maps the overclosure ``d = -g_N`` to a pressure ``p(d)`` and its slope,
and gives the clearance cutoff beyond which a slave node gets no element.
The normal force is ``F_N = A_p p(d)`` with slope ``dF_N/dg_N = -A_p p'(d)``.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from dolfinx_friction.contact.shapes import Array

_EXP_CAP = 23.0  # CalculiX caps the exponential force at e^23 force units


class Law:
    """Base class: ``pressure(d) -> (p, dp/dd)`` and ``cutoff(A_p)``."""

    def pressure(self, d: Array) -> tuple[Array, Array]:
        raise NotImplementedError

    def cutoff(self, area: Array) -> Array:
        raise NotImplementedError

    def normal_force(self, g_N: Array, area: Array) -> tuple[Array, Array]:
        """``F_N`` (> 0 in compression) and ``dF_N/dg_N`` at clearances ``g_N``."""
        p, dp = self.pressure(-np.asarray(g_N, dtype=float))
        return area * p, -area * dp

    def bilinear(self, area: Array) -> Optional[tuple[Array, Array, float]]:
        """``(k, s, width)``: ``F_N = k max(d, 0) - s`` [force / length, force] where
        ``|d| >= width`` [length] (the law's regularisation lies within), or None where the
        law is not of that form."""
        return None


@dataclass(frozen=True)
class Linear(Law):
    """Arctan-regularised linear law: ``p = K d (1/2 + atan(d/eps)/pi)``, ``eps = pi sigma_inf/K``."""

    K: float
    sigma_inf: float
    c0: float = 1e-3

    @property
    def eps(self) -> float:
        return np.pi * self.sigma_inf / self.K

    def pressure(self, d):
        z = d / self.eps
        h = 0.5 + np.arctan(z) / np.pi
        return self.K * d * h, self.K * h + self.K * z / (np.pi * (1.0 + z * z))

    def cutoff(self, area):
        return _cutoff(self.c0 * np.sqrt(area), area)

    def bilinear(self, area):
        """``K A_p``, the tension plateau ``sigma_inf A_p`` and ``10 eps``: at ``|d| = c eps``
        ``p`` is ``K max(d, 0) - sigma_inf`` within ``sigma_inf / (3 c^2)``."""
        area = np.asarray(area, dtype=float)
        return self.K * area, self.sigma_inf * area, 10.0 * self.eps


@dataclass(frozen=True)
class Exponential(Law):
    """``p = p0 exp(beta d)``, ``beta = ln(100)/c0``; force capped at e^23 (CalculiX's guard).

    Beyond the cap the force is constant and its slope is the exact zero, not
    CalculiX's ``-beta' F_N`` (docs/theory.md §10.10).
    """

    c0: float
    p0: float

    @property
    def beta(self) -> float:
        return np.log(100.0) / self.c0

    def pressure(self, d):
        if self.p0 < 1e-30:
            return np.zeros_like(d), np.zeros_like(d)
        # p0 exp(beta d) with the exponent capped where p would exceed e^23 / A ~ handled in force
        e = np.exp(np.minimum(self.beta * d, 700.0))
        return self.p0 * e, self.beta * self.p0 * e

    def normal_force(self, g_N, area):
        F, dF = super().normal_force(g_N, area)
        with np.errstate(divide="ignore"):
            capped = self.beta * (-np.asarray(g_N)) > _EXP_CAP - np.log(area * self.p0)
        capped = capped & (self.p0 >= 1e-30)  # p0 < 1e-30: zero force, never the cap
        return np.where(capped, np.exp(_EXP_CAP), F), np.where(capped, 0.0, dF)

    def cutoff(self, area):
        return np.where(area > 0, self.c0, 1e-10)


@dataclass(frozen=True)
class Tabular(Law):
    """Piecewise linear through ``(pressure, overclosure)`` pairs; constant outside the table."""

    pressures: tuple[float, ...]
    overclosures: tuple[float, ...]

    def __post_init__(self):
        d = np.array(self.overclosures, dtype=float)
        for k in range(1, len(d)):  # CalculiX forces consecutive points 1e-10 apart
            d[k] = max(d[k], d[k - 1] + 1e-10)
        object.__setattr__(self, "overclosures", tuple(d))

    def pressure(self, d):
        p = np.asarray(self.pressures, dtype=float)
        x = np.asarray(self.overclosures, dtype=float)
        seg = np.clip(np.searchsorted(x, d, side="right") - 1, 0, len(x) - 2)
        slope = (p[seg + 1] - p[seg]) / (x[seg + 1] - x[seg])
        inside = (d >= x[0]) & (d < x[-1])
        value = np.interp(d, x, p)
        return value, np.where(inside, slope, 0.0)

    def cutoff(self, area):
        return _cutoff(1e-3 * np.sqrt(area), area)


def _cutoff(c: Array, area: Array) -> Array:
    return np.where(np.asarray(area) > 0, c, 1e-10)
