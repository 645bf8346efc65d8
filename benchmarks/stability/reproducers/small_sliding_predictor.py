"""Reproducer: with ``pairing_iterations = 1`` the ironing drag accepts increments without contact.

Fixed in a68a938 (nodes closed at the last commit keep an element at the first pairing;
pinned by ``test_pairing_once_after_a_predictor_keeps_contact``).  Now all 20 drag
increments keep 4 nodes in contact, with a vertical die force of -3.42 .. -3.58.  What follows
describes the solver before that commit.

The ironing demo (coarse: 40 x 8 block elements, 16 elements on the die's arc), drag per
increment half a die element, ``pairing_iterations = 1`` (CalculiX's SMALL SLIDING: pair
once, in the first Newton iteration).  Expected: 3-4 block nodes under the die in every
increment.  Observed: from the 9th drag increment on, every other increment converges with
0 nodes in contact and a zero die reaction, although the die stays 0.5 deep in the block.

Why: the first iteration pairs at the *predicted* state (``Solver.run`` adds the previous
increment's rate, ``u += dtau * rate``, before Newton).  After an increment without
contact the rate carries the nodes into the die, after one with contact it lifts them out
beyond the cutoff; pairing once at that extrapolated state finds no node within the
cutoff, the element set stays empty for the whole increment, and the uncoupled problem
converges at once.  With the predictor disabled the same scene keeps 1-4 nodes in
contact in every increment (checked by patching the two predictor lines out of a copy of
``solver.py``).  Pairing on the start-of-increment state, or keeping the elements of the
nodes in contact at the last commit (as the re-pairing does with its hysteresis), would
avoid it.

    PYTHONPATH=. python benchmarks/stability/reproducers/small_sliding_predictor.py
"""
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

import _scenes  # noqa: E402
from dolfinx_friction.scene.runner import run  # noqa: E402

scene, info = _scenes.ironing_scene({"pairing": 1, "slide_faces": 0.5})
result = run(scene, write=False)
die = info["reaction"]
for inc in result.increments:
    print(f"{inc.step_name:5s} {inc.increment:2d}  {inc.active} nodes in contact  "
          f"R({die}) = {inc.reactions[die].round(3)}")
