"""Reproducer: an initial overclosure being ramped out is reported as 'penalty too soft'.

Fixed in a68a938 (the warning measures the overclosure the law acts on, ramp offset
included; pinned by ``test_ramped_initial_overclosure_is_not_a_soft_penalty``).  Now the
reported overclosure is 0.1 .. 0.4 % of the spacing and nothing is warned.  What follows
describes the solver before that commit.

The block starts 0.0625 (half its node spacing) inside the foundation; its top is lifted so
that it ends in the zero-gap state; the press step has 4 increments.  The overclosure is
ramped out over the step (docs/theory.md §3.4): the law sees only a small part of it and
the forces are right.  But ``ContactInteraction.penetration`` measures ``-g_N`` without the
ramp offset, so the run warns 'overclosure reaches 75.1 % of the slave node spacing ...
the penalty K is too soft' at t = 0.25, when the overclosure the law acts on is < 1 %.
(The corner nodes count with half the spacing, hence 75 % for a 50 % overlap.)

    PYTHONPATH=. python benchmarks/stability/reproducers/ramp_warning.py
"""
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

import _scenes  # noqa: E402
from dolfinx_friction.scene.runner import run  # noqa: E402

scene, _ = _scenes.block_scene({"gap": -0.5, "press_increments": 4, "slide": 0, "k": 10})
result = run(scene, write=False)
for inc in result.increments:
    print(f"t = {inc.t:.2f}  reported overclosure / spacing = "
          f"{max(inc.penetration.values()):.3f}  R(block_top) = {inc.reactions['block_top'].round(3)}")
