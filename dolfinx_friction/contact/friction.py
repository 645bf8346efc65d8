"""Coulomb friction by radial return (docs/theory.md §6) and its tangent (§7.1-7.2).

History is per slave node: ``w`` (slave minus master displacement at the
projection), ``g_T`` (accumulated tangential relative displacement) and
``g_p`` (its slip part).  :class:`FrictionState` holds one such triple per
slave node; the return map never modifies its input, it returns the trial
values, which the solver commits only when an increment converges.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dolfinx_friction.contact.shapes import Array


@dataclass
class FrictionState:
    """Per-slave-node history ``(w, g_T, g_p)``, each of shape (n, gdim)."""

    w: Array
    g_T: Array
    g_p: Array

    @classmethod
    def zeros(cls, n: int, gdim: int) -> "FrictionState":
        return cls(np.zeros((n, gdim)), np.zeros((n, gdim)), np.zeros((n, gdim)))

    def copy(self) -> "FrictionState":
        return FrictionState(self.w.copy(), self.g_T.copy(), self.g_p.copy())

    def take(self, index: np.ndarray) -> "FrictionState":
        return FrictionState(self.w[index], self.g_T[index], self.g_p[index])

    def put(self, index: np.ndarray, other: "FrictionState") -> None:
        self.w[index], self.g_T[index], self.g_p[index] = other.w, other.g_T, other.g_p


@dataclass
class ReturnMap:
    """Result of the radial return for a batch of slave nodes."""

    F_T: Array  # (n, gdim) tangential force of the slave on the master
    slip: np.ndarray  # (n,) bool
    F_trial: Array  # (n, gdim)
    dgamma: Array  # (n,) consistency increment (0 in stick)
    g_p: Array  # (n, gdim) trial slip part


def radial_return(g_T: Array, g_p_n: Array, K_t: Array, mu: float, F_N: Array) -> ReturnMap:
    """Stick if ``|F_tr| < mu |F_N|`` (strict) or ``|F_tr| = 0``, else slip (§6.3)."""
    F_trial = K_t[:, None] * (g_T - g_p_n)
    norm = np.linalg.norm(F_trial, axis=1)
    limit = mu * np.abs(F_N)
    slip = (norm >= limit) & (norm > 0.0)
    safe = np.where(slip, norm, 1.0)
    e_T = F_trial / safe[:, None]
    F_T = np.where(slip[:, None], limit[:, None] * e_T, F_trial)
    dgamma = np.where(slip, (norm - limit) / K_t, 0.0)
    return ReturnMap(F_T, slip, F_trial, dgamma, g_p_n + dgamma[:, None] * e_T)


def tangent(rm: ReturnMap, K_t: Array, mu: float, F_N: Array, G: Array, dF_N: Array) -> Array:
    """``dF_T/du_i`` (n, gdim, nodes, gdim) from ``G_i = dg_T/du_i`` and ``dF_N/du_i``.

    ``G`` has shape (n, gdim, nodes, gdim), ``dF_N`` (n, nodes, gdim).
    stick: ``K_t G_i``; slip: ``mu|F_N| K_t/|F_tr| (I - e e) G_i + mu e (x) sign(F_N) dF_N/du_i``.
    """
    out = K_t[:, None, None, None] * G
    s = np.flatnonzero(rm.slip)
    if s.size:
        norm = np.linalg.norm(rm.F_trial[s], axis=1)
        e = rm.F_trial[s] / norm[:, None]
        factor = mu * np.abs(F_N[s]) * K_t[s] / norm
        Gs = G[s]
        projected = Gs - e[:, :, None, None] * np.einsum("nc,ncid->nid", e, Gs)[:, None]
        N = np.sign(F_N[s])[:, None, None] * dF_N[s]
        out[s] = factor[:, None, None, None] * projected + mu * e[:, :, None, None] * N[:, None]
    return out
