"""Reproducer: a diverging Newton iterate detaches the contact, and the increment is accepted.

The ironing demo (coarse: 40 x 8 block elements, 16 elements on the die's arc), penalty
K = 100 E/h, drag of one die element per increment, no line search (exact tangent; the
numbers below are from that run).  The second drag
increment is a retry after a cutback (t = 1.1 -> 1.125).  Its residuals go 2.0, 5e2, 2.6e2,
2.9e4: the third iterate throws the four block nodes under the die far away (one to
(105, -51)).  All of them lose their elements.  The search that this triggers
(``Solver._pair``: a node slid past all its candidate faces) runs at that iterate and finds
no candidate faces near the nodes.  The nodes are marked ``off_surface``, so no later
iteration searches again.  The next iterate is the uncoupled problem.  It converges at
once (3.5e-11) with 0 nodes in contact and a zero die force, although the die stays 0.5
deep in the block.  The run warns "4 slave node(s) in contact slid off the master surface
at t = 1.125".  Then it goes on: the next increment pairs the nodes again.

Before commit a68a938 the candidates of the increment's first search stayed.  The nodes
paired again at the next iterate, and the same run converged with 4 cutbacks and
contact in every increment.  The same thing happens with ``mu = 0.6, stick slope = 10 E/h``
(``ironing_stick_mu``): an increment is accepted with 2 nodes in contact, the friction
force reversed, the normal force 2.5 times too large and 17.6 % overclosure.

Since 6a512ff (GMRES with a reused factorisation, its iteration budget set from measured
times) runs are not bit-reproducible, and which tangent hits the detach varies: in one map
run the exact tangent failed instead and the CalculiX tangent lost the contact.  So this
script runs both and prints the drag increments up to the first one after a detach.

    PYTHONPATH=. python benchmarks/stability/reproducers/detach_after_divergence.py
"""
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

import _scenes  # noqa: E402
from dolfinx_friction.scene.runner import run  # noqa: E402
from dolfinx_friction.scene.driver import ConvergenceError  # noqa: E402

for tangent in ("consistent", "calculix"):
    print(f"--- tangent = {tangent}")
    scene, info = _scenes.ironing_scene({"k": 100.0, "slide_faces": 1.0, "tangent": tangent})
    try:
        result = run(scene, write=False)
    except ConvergenceError as exc:
        print("ConvergenceError:", exc)
        continue
    die = info["reaction"]
    detached = [i for i, inc in enumerate(result.increments) if sum(inc.detached.values())]
    last = detached[0] + 1 if detached else 5
    for inc in result.increments[4:last + 1]:
        print(f"{inc.step_name:5s} {inc.increment:2d} t = {inc.t:.4f}  {inc.active} nodes in "
              f"contact  detached {sum(inc.detached.values())}  R({die}) = "
              f"{inc.reactions[die].round(3)}  residuals "
              f"{' '.join(f'{r:.1e}' for r in inc.residuals)}")
    print(f"converged with {result.summary.cutbacks} cutbacks; increments without contact: "
          f"{sum(1 for inc in result.increments if inc.active == 0)}")
