"""Every accepted increment balances and obeys Coulomb (issue 23).

The reproducer: the ironing demo with its die 10^7 times stiffer than the block and
Newton's ``rtol`` at 1e-6.  The first press increment starts from the die's prescribed
jump, a residual about 10^6 times the contact force it ends with; the old test (``rtol``
times that first residual) accepted it after one iteration with the die unbalanced by 73
times the forces.  Newton's target is now ``rtol`` times the smaller of the first residual
and the forces; the postcondition (:meth:`BlockProblem.postcondition`) would cut back an
increment that still came out unbalanced.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import dolfinx_friction
from dolfinx_friction.scene.runner import run
from dolfinx_friction.scene.toml import load_scene

DEMOS = Path(__file__).resolve().parents[2] / "demos"


def _stiff_press(increments: int = 10):
    scene = load_scene(DEMOS / "ironing.toml",
                       ["body.1.E=1e8", "step.0.newton_rtol=1e-6",
                        f"step.0.increments={increments}"])
    return dataclasses.replace(scene, steps=scene.steps[:1])


def test_stiff_indenter_balances_from_first_contact():
    """Every press increment balances to 1e-5 of the forces (measured 2e-7 to 4e-7 on
    1 and 2 ranks: the round-off of a die 10^7 times stiffer; the old code left 73 in the
    first), and the die's reaction is what the contact transmits."""
    increments = run(_stiff_press(), write=False).increments
    assert len(increments) == 10
    for inc in increments:
        assert inc.imbalance <= 1e-5 * inc.force, (inc.increment, inc.imbalance, inc.force)
        assert inc.iterations >= 2 or inc.increment > 1  # not accepted at its first iterate
    # the die is held by die_top only, the block by block_bottom only: the reactions balance
    last = increments[-1]
    R_die, R_block = last.reactions["die_top"], last.reactions["block_bottom"]
    np.testing.assert_allclose(R_die, -R_block, atol=1e-5 * np.abs(R_die).max())


def test_failed_increment_is_the_root_convergence_error():
    """A run that fails raises the package root's ConvergenceError, naming step and
    increment (1 Newton iteration allowed, no cutback)."""
    scene = load_scene(DEMOS / "ironing.toml", ["step.0.max_iterations=1",
                                                "step.0.max_cutbacks=0"])
    with pytest.raises(dolfinx_friction.ConvergenceError,
                       match=r"step 0 \('press'\), increment 1 ") as info:
        run(scene, write=False)
    assert info.value.increment == 1 and info.value.cutbacks == 1
