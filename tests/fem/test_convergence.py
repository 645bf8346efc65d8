"""Newton's convergence tests: ``convergence = "reactions"`` against the strict residual test.

"reactions" also stops when the reactions and displacements no longer change (the
residual below ``reaction_tol`` of the force scale, the corrections contracting, no
contact change, the whole step taken).  It must give the strict test's reactions in
no more iterations (fewer on two of the three demos), serially and under ``mpirun -n 2``
(the issue's bar is 1e-6 relative in every increment; measured 1.6e-12 .. 1.7e-9,
asserted 1e-8).  Chord steps (finite strain) give the answer of a new Jacobian in every
step with fewer factorisations.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from dolfinx_friction import Newton, solve_steps
from dolfinx_friction.scene.runner import run
from dolfinx_friction.scene.model import Step
from dolfinx_friction.scene.toml import SceneError, load_scene

DEMOS = Path(__file__).resolve().parents[2] / "demos"


def _run(name: str, steps: int, mode: str):
    sets = [f'step.{k}.convergence="{mode}"' for k in range(steps)]
    return run(DEMOS / f"{name}.toml", write=False, overrides=sets).increments


@pytest.mark.parametrize("name, steps, saves", [("hertz_cylinder", 1, False),
                                                ("incline", 2, True), ("sliding_block", 2, True)])
def test_reactions_test_gives_the_strict_reactions_in_fewer_iterations(name, steps, saves):
    """``saves``: fewer iterations in all (Hertz: 35 and 35 since the slave areas are those
    of the converged start of each increment, the strict test's 38 before)."""
    strict, loose = _run(name, steps, "residual"), _run(name, steps, "reactions")
    assert [(i.step, i.t) for i in strict] == [(i.step, i.t) for i in loose]
    worst = 0.0
    for a, b in zip(strict, loose):
        for group, R in a.reactions.items():
            worst = max(worst, np.abs(b.reactions[group] - R).max() / np.abs(R).max())
    assert worst < 1e-8
    assert all(b.iterations <= a.iterations for a, b in zip(strict, loose))
    assert sum(b.iterations for b in loose) < sum(a.iterations for a in strict) or not saves


def test_unknown_convergence_test_is_refused_naming_the_key():
    with pytest.raises(ValueError, match="convergence = 'forces'"):
        Newton(convergence="forces")
    with pytest.raises(SceneError, match=r"step.convergence"):
        Step("press", convergence="forces")
    with pytest.raises(SceneError, match=r"step.reaction_tol"):
        Step("press", reaction_tol=0.0)
    with pytest.raises(SceneError, match='step.0.convergence = "nope": must be one of'):
        load_scene(DEMOS / "incline.toml", ['step.0.convergence="nope"'])


def test_stalled_increments_are_cut_back_to_the_same_answer():
    """Ten times the default penalty on the Hertz demo, Newton's own steps
    (``solver.solve_statuses = false``; solved statuses converge there in 16 iterations
    without a cutback): the statuses at the edge of the zone cycle.  Giving up after
    ``stall_iterations`` without a new lowest residual (and cutting back) reaches the same
    reactions in fewer iterations (measured 82 -> 69 with 6, the same cutback, reactions
    equal to 1e-8; 1 gives up at any rise of the residual and cuts back 16 times), and
    never on the last cutback.  Runs whose last increments differ agree
    to 2e-6 only: the slave areas are measured at each increment's start (measured 1.5e-6
    between 3 and 30 equal increments)."""
    base = ["contact.0.K=1e7", "step.0.increments=3", "solver.solve_statuses=false"]
    runs = {n: run(DEMOS / "hertz_cylinder.toml", write=False,
                   overrides=base + [f"step.0.stall_iterations={n}"]) for n in (0, 6, 1)}
    final = {n: r.increments[-1] for n, r in runs.items()}
    assert all(abs(i.t - 1.0) < 1e-12 for i in final.values())
    for n, tolerance in ((6, 1e-8), (1, 2e-6)):
        for group, R in final[0].reactions.items():
            assert np.abs(final[n].reactions[group] - R).max() < tolerance * np.abs(R).max()
    assert runs[6].summary.newton_iterations < runs[0].summary.newton_iterations
    assert runs[1].summary.cutbacks > runs[0].summary.cutbacks
    with pytest.raises(SceneError, match=r"step.stall_iterations"):
        Step("press", stall_iterations=-1)


def test_chord_steps_give_the_newton_answer_with_fewer_factorisations():
    """A Neo-Hookean block pressed onto a Neo-Hookean foundation and slid with friction:
    Newton with chord steps (the default; the last factorisation solves a step after a
    whole one that changed no contact status and cut the residual tenfold) reaches the
    displacements of a new Jacobian in every step (``chord=0``) to the convergence test's
    precision (measured 4e-14 of the largest) in fewer factorisations (13 -> 6); with the
    user's own Krylov method around the factorisation too, which chord steps leave as it
    was."""
    from tests.fem.test_contact_api import block_and_foundation, two_bodies
    spaces = block_and_foundation(1, 1)
    answers, work = [], []
    own = {"ksp_type": "gmres", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps",
           "ksp_rtol": 1e-12}
    for newton in (Newton(chord=0.0), Newton(), Newton(petsc_options=own)):
        problem, _, g = two_bodies(spaces=spaces)
        solve_steps(problem, lambda t: g.value.__setitem__(slice(None), (0.0, -0.03 * t)), 3,
                    newton=newton)
        solve_steps(problem, lambda t: g.value.__setitem__(slice(None), (0.02 * t, -0.03)), 2,
                    newton=newton)
        answers.append(problem.x.getArray().copy())
        work.append((newton.linear.factorisations, newton.linear.chord_solves))
    scale = MPI.COMM_WORLD.allreduce(np.abs(answers[0]).max(), op=MPI.MAX)
    for answer in answers[1:]:
        worst = MPI.COMM_WORLD.allreduce(np.abs(answer - answers[0]).max(), op=MPI.MAX)
        assert worst < 1e-9 * scale
    (exact, none), (chord, solves), (_, own_solves) = work
    assert none == 0 and solves > 0 and chord < exact and own_solves > 0
    assert newton.linear.settings()["ksp_type"] == "gmres"
