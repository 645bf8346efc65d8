"""The assembled Jacobian against finite differences of the residual, for the tangent checks.

:func:`derivative_error` compares ``J dv`` with the derivative of the residual along ``dv``,
estimated by central differences ``D(h) = (R(x + h dv) - R(x - h dv)) / 2h`` at steps h,
h/2, h/4, ... and Richardson's extrapolation ``(4 D(h/2) - D(h)) / 3``, which removes the
``h^2`` term, until two successive extrapolations agree, and takes the best of these
estimates (a tangent off by more than they differ shows in every one of them).  A plain
central difference is off by ``C h^2``, and ``C`` is large near a slave node whose contact force is almost zero
(smooth, but its slip direction turns fast): a fixed step left errors of 1e-7..6e-4 with a
correct tangent (the turning plane on 2 ranks, where another partition perturbs other
nodes; quadratic faces), each 4/3 of the change from h to h/2, the mark of truncation.
A direction along which the extrapolations do not settle crosses a kink (a node changing
status within the step) and tests no derivative: :func:`derivative_error` returns None
there and :func:`tangent_error` draws another.
"""
from __future__ import annotations

from typing import Callable, Iterator, Optional

import numpy as np
from petsc4py import PETSc

Residual = Callable[[PETSc.Vec], PETSc.Vec]  # x -> a new vector R(x), the pairing frozen


def central_difference(residual: Residual, x: PETSc.Vec, dv: PETSc.Vec, h: float) -> PETSc.Vec:
    """``(R(x + h dv) - R(x - h dv)) / 2h``."""
    xp, xm = x.copy(), x.copy()
    xp.axpy(h, dv)
    xm.axpy(-h, dv)
    return (residual(xp) - residual(xm)) / (2 * h)


def derivative_error(residual: Residual, x: PETSc.Vec, J: PETSc.Mat, dv: PETSc.Vec, h: float,
                     kink: float = 1e-6, halvings: int = 4) -> Optional[float]:
    """``|J dv - dR/dv| / |J dv|`` for the best of the estimates of the derivative: central
    differences at steps ``h / 2^k`` and their extrapolations, taken until two successive
    extrapolations agree within ``kink |J dv|``; None if they never do (a kink)."""
    Jdv = J.createVecLeft()
    J.mult(dv, Jdv)
    size = Jdv.norm()
    best, last_difference, last_estimate = np.inf, None, None
    for k in range(halvings + 1):
        difference = central_difference(residual, x, dv, h / 2 ** k)
        best = min(best, (difference - Jdv).norm() / size)
        if last_difference is not None:
            estimate = (4 * difference - last_difference) / 3
            best = min(best, (estimate - Jdv).norm() / size)
            if last_estimate is not None and (estimate - last_estimate).norm() <= kink * size:
                return best
            last_estimate = estimate
        last_difference = difference
    return None


def tangent_error(residual: Residual, x: PETSc.Vec, J: PETSc.Mat,
                  directions: Iterator[PETSc.Vec], h: float, needed: int = 3,
                  draws: int = 12) -> float:
    """The worst :func:`derivative_error` over the first ``needed`` of ``draws`` directions
    without a kink (AssertionError if fewer)."""
    errors = []
    for _, dv in zip(range(draws), directions):
        error = derivative_error(residual, x, J, dv, h)
        if error is not None:
            errors.append(error)
            if len(errors) == needed:
                return max(errors)
    raise AssertionError(f"only {len(errors)} of {draws} directions free of kinks")


def random_directions(template: PETSc.Vec, rng: np.random.Generator,
                      held: Optional[np.ndarray] = None) -> Iterator[PETSc.Vec]:
    """Random vectors like ``template``, zero in the local rows ``held``, their largest
    entry 1 in magnitude (a step h moves no unknown by more than h)."""
    while True:
        dv = template.duplicate()
        values = rng.standard_normal(template.getLocalSize())
        if held is not None:
            values[held] = 0.0
        dv.setArray(values)
        dv.scale(1.0 / dv.norm(PETSc.NormType.INFINITY))
        yield dv


def coordinate_noise(problem, seed: int = 0) -> np.ndarray:
    """Owned values like ``problem.x`` in [-1, 1), a hash of each dof's node coordinates and
    component (and of the obstacles' indices): the same numbers at the same dofs on any
    number of ranks, so a perturbed iterate does not depend on the partition."""
    def hashed(phase: np.ndarray) -> np.ndarray:
        return 2.0 * np.modf(np.abs(np.sin(phase) * 43758.5453))[0] - 1.0
    d = problem.gdim
    values = np.zeros(problem.x.getLocalSize())
    for k, V in enumerate(problem.spaces):
        X = V.tabulate_dof_coordinates()[: V.dofmap.index_map.size_local]
        phase = (X @ np.array([12.9898, 78.233, 37.719]))[:, None] + 3.7 * np.arange(d) \
            + 7.1 * k + 1.9 * seed
        values[problem.block_slice(k)] = hashed(phase).ravel()
    for k in range(problem.n_obstacles):
        rows = problem.obstacle_rows(k)
        values[rows] = hashed(5.3 * k + 3.7 * np.arange(len(rows)) + 1.9 * seed + 0.5)
    return values


def scene_tangent_error(problem, h: float = 1e-7) -> float:
    """:func:`tangent_error` of a solved scene's system (no constrained rows) at its
    solution perturbed by 1e-5, from a start-of-increment state 0.999 times it, every
    pair paired there and frozen."""
    system = problem.system
    system.prescribe(np.zeros(0, dtype=np.int64), np.zeros(0))
    x = system.x
    start = x.copy()
    start.scale(0.999)
    rng = np.random.default_rng(problem.comm.rank)
    x.setArray(x.getArray() + 1e-5 * rng.standard_normal(x.getLocalSize()))
    pairs = list(problem.pairs.values())
    for pair in pairs:
        pair.begin(x, start=start)
        pair.update(x)
    J = system.jacobian(x)

    def residual(y: PETSc.Vec) -> PETSc.Vec:
        for pair in pairs:
            pair.update(y, pairing=False)
        system.residual(y, system.b)
        return system.b.copy()
    return tangent_error(residual, x.copy(), J, random_directions(x, rng), h)
