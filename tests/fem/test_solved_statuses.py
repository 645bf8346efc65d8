"""Newton steps that solve for the frictionless contact statuses (``nls.normal_qp``).

The program's minimiser satisfies the complementarity conditions and is the one solution
an enumeration of every status set finds; on the Hertz demo (linear bodies, frictionless,
the condensed path) the steps reach the reactions of Newton's own steps in fewer
iterations, serially and under MPI.
"""
from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse

from dolfinx_friction.nls.normal_qp import Elements, normal_forces
from dolfinx_friction.scene.build import ContactProblem
from dolfinx_friction.scene.driver import Solver
from dolfinx_friction.scene.toml import load_scene

DEMOS = Path(__file__).resolve().parents[2] / "demos"


def _enumerated(M: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The solution of ``lam >= 0, M lam - q >= 0, lam (M lam - q) = 0`` by trying every
    set of positive forces."""
    n = len(q)
    for positive in itertools.product((False, True), repeat=n):
        on = np.flatnonzero(positive)
        lam = np.zeros(n)
        lam[on] = np.linalg.solve(M[np.ix_(on, on)], q[on]) if len(on) else []
        w = M @ lam - q
        if (lam[on] > 0).all() and (w[~np.asarray(positive)] >= -1e-12).all():
            return lam
    raise AssertionError("no status set solves the problem")


@pytest.mark.parametrize("seed", range(5))
def test_normal_forces_solve_the_complementarity_problem(seed):
    """Random compliances of 10 nodes (symmetric positive semi-definite, rank 7: fewer
    independent directions than nodes, as on a master face), stiff penalties, mixed
    overclosures: the forces are the enumeration's to 1e-12 of the largest (measured
    7.5e-14)."""
    rng = np.random.default_rng(seed)
    n = 10
    V = rng.standard_normal((n, 7))
    W = V @ V.T
    k = 10.0 ** rng.uniform(2, 4, n)
    q = rng.standard_normal(n)
    lam = normal_forces(W, k, q)
    expected = _enumerated(W + np.diag(1.0 / k), q)
    assert (lam >= 0).all()
    np.testing.assert_allclose(lam, expected, atol=1e-12 * np.abs(expected).max())


def test_no_elements_no_forces():
    assert normal_forces(np.zeros((0, 0)), np.zeros(0), np.zeros(0)).shape == (0,)


def test_no_forces_where_the_program_is_not_positive_definite():
    """A body that only the contact holds leaves ``K`` singular but for round-off: ``W``
    has its rigid motion as a direction some 1e15 times the others (measured on the patch
    test's upper block), a node of no area has no stiffness: no forces (Newton's own step
    is taken)."""
    rng = np.random.default_rng(3)
    V = rng.standard_normal((6, 6))
    W, k, q = V @ V.T, np.full(6, 1e3), rng.standard_normal(6)
    assert normal_forces(W, k, q) is not None
    rigid = np.ones(6) / np.sqrt(6)
    assert normal_forces(W + 2.6e15 * np.outer(rigid, rigid), k, q) is None
    k[2] = 0.0
    assert normal_forces(W, k, q) is None


def test_only_decisive_status_changes_count():
    """A status the program changes counts only where the overclosure, now and after the
    step, is at least the law's width from 0 (within it the law is smooth)."""
    el = Elements(np.zeros(0, np.int64), scipy.sparse.csr_matrix((3, 0)), np.array(
        [1e-3, -1e-3, 1e-9]), np.zeros(3), np.ones(3), np.zeros(3), np.full(3, 1e-6),
        np.array([True, False, True]))
    assert not el.changes(np.array([1.0, 0.0, 1.0]), np.array([1e-3, -1e-3, 2e-9]))
    assert not el.changes(np.array([1.0, 0.0, 0.0]), np.array([1e-3, -1e-3, -1e-3]))
    assert not el.changes(np.array([0.0, 0.0, 1.0]), np.array([-1e-7, -1e-3, 1e-9]))
    assert el.changes(np.array([0.0, 0.0, 1.0]), np.array([-1e-5, -1e-3, 1e-9]))
    assert el.changes(np.array([1.0, 1.0, 1.0]), np.array([1e-3, 1e-3, 1e-9]))


def _hertz(solve_statuses: bool):
    """The Hertz demo with K = 1e7 (the statuses at the edge of the zone flip back and
    forth under Newton's own steps), 4 increments."""
    scene = load_scene(DEMOS / "hertz_cylinder.toml", ["contact.0.K=1e7"])
    solver = Solver(ContactProblem(scene))
    solver.newton.solve_statuses = solve_statuses
    increments = []
    solver.run(increments.append)
    return increments, solver


def test_solved_statuses_reach_newtons_reactions_in_fewer_iterations():
    """The same reactions as Newton's own steps (measured 1.1e-13 of the largest) in fewer
    iterations (measured 18 against 49, 4 increments of 7,572 dofs, on 1 and 2 ranks); the
    steps are counted in the summary."""
    solved, solver = _hertz(True)
    plain, reference = _hertz(False)
    assert solver.linear.contact_steps > 0 and reference.linear.contact_steps == 0
    assert solver.summary.linear_solves["contact_steps"] == solver.linear.contact_steps
    assert [(i.step, i.t) for i in solved] == [(i.step, i.t) for i in plain]
    for a, b in zip(solved, plain):
        for group, R in b.reactions.items():
            np.testing.assert_allclose(a.reactions[group], R, atol=1e-12 * np.abs(R).max())
    assert solver.summary.newton_iterations < reference.summary.newton_iterations
