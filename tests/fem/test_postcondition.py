"""The postcondition of an increment (:meth:`BlockProblem.postcondition`): what it finds
in a deliberately corrupted state, and what :func:`solve_steps` does with an increment
that fails it.  Serial and under ``mpirun -n 2``."""
from __future__ import annotations

import numpy as np
import pytest

import dolfinx_friction
from dolfinx_friction import solve_steps
from tests.fem.test_contact_api import press_and_slide, two_bodies


def test_a_converged_increment_passes_and_a_corrupted_one_does_not():
    """After a frictional slide every body balances far within the bound (measured at most
    1.8e-2 of it on 1-3 ranks and in sid: a chord step's linear convergence lands nearer
    the tolerance than a Newton step's); the same state with the block's displacement
    scaled by 1.001 (its reactions and contact forces no longer the converged ones) leaves
    it unbalanced by far more, and the postcondition names it."""
    problem, contact, g = two_bodies()
    records = press_and_slide(problem, contact, g)
    newton = dolfinx_friction.Newton()
    tolerance = newton.residual_tolerance(problem)
    allowed = np.sqrt(problem.free_rows()) * tolerance
    assert problem.postcondition(tolerance) == ""
    assert (np.abs(problem.imbalance()) <= 1e-2 * allowed).all()
    assert all(r.imbalance <= 5e-2 * np.sqrt(problem.free_rows()).max() * tolerance
               for r in records)
    corrupted = problem.x.copy()
    values = corrupted.getArray()
    values[problem.block_slice(0)] *= 1.001
    corrupted.setArray(values)
    contact.update(corrupted, pairing=False)
    problem.residual(corrupted, problem.b)
    message = problem.postcondition(tolerance)
    assert message.startswith("body 0 unbalanced by "), message
    assert (np.abs(problem.imbalance()) > 10 * allowed).any()


def test_an_increment_that_fails_it_is_cut_back_and_then_refused(monkeypatch):
    """An increment whose slave nodes exceed Coulomb (as a kernel that broke the radial
    return would leave them) is cut back like a diverged one, and after the last cutback
    the run stops with the reason; ``postcondition=False`` accepts it."""
    problem, contact, g = two_bodies()
    monkeypatch.setattr(contact, "coulomb_excess", lambda: 1.0)
    history = Counter()
    with pytest.raises(dolfinx_friction.ConvergenceError,
                       match="friction force exceeds mu times its normal force") as info:
        solve_steps(problem, lambda t: g.value.__setitem__(slice(None), (0.0, -0.03 * t)), 1,
                    max_cutbacks=2, history=[history])
    assert info.value.increment == 1 and info.value.cutbacks == 3
    assert (history.commits, history.rollbacks) == (0, 3)  # the user's state with the contact's
    problem, contact, g = two_bodies()
    monkeypatch.setattr(contact, "coulomb_excess", lambda: 1.0)
    records = solve_steps(problem, lambda t: g.value.__setitem__(slice(None), (0.0, -0.03 * t)),
                          1, postcondition=False, history=[history])
    assert len(records) == 1 and (history.commits, history.rollbacks) == (1, 3)


class Counter:
    """A user's history (say the state of a plasticity model): counts commits, rollbacks."""

    def __init__(self):
        self.commits = self.rollbacks = 0

    def commit(self):
        self.commits += 1

    def rollback(self):
        self.rollbacks += 1
