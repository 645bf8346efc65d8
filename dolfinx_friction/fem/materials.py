"""Isotropic elastic constants and the out-of-plane thickness, from plain numbers.

``E`` is Young's modulus [force / area], ``nu`` Poisson's ratio (-1 < nu < 1/2).  The
one place where the scene's bodies, the loads and the CalculiX deck get them.
"""
from __future__ import annotations

__all__ = ["bulk_modulus", "lame", "out_of_plane"]


def lame(E: float, nu: float, plane_stress: bool = False) -> tuple[float, float]:
    """``(lam, mu)``: Lamé's first parameter and the shear modulus [force / area].

    ``mu = E / (2 (1 + nu))``, ``lam = E nu / ((1 + nu) (1 - 2 nu))``; with
    ``plane_stress`` the ``lam`` of a 2D plane-stress body, ``2 lam mu / (lam + 2 mu)``.
    """
    mu = E / (2.0 * (1.0 + nu))
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    if plane_stress:
        lam = 2.0 * lam * mu / (lam + 2.0 * mu)
    return lam, mu


def bulk_modulus(E: float, nu: float) -> float:
    """``kappa = E / (3 (1 - 2 nu))`` [force / area]."""
    return E / (3.0 * (1.0 - 2.0 * nu))


def out_of_plane(thickness: float, gdim: int) -> float:
    """The thickness [length] that areas and volumes of a body are multiplied by:
    ``thickness`` for a 2D (plane) body, 1 in 3D."""
    return thickness if gdim == 2 else 1.0
