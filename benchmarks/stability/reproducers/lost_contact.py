"""Reproducer: an increment in which every contact element is lost is accepted as converged.

Elastic block (8 x 4 quads, 1 x 0.5) pressed 0.01 into an elastic foundation whose top has
master faces of the block's size (h = 0.125), default penalty, mu = 0.3; then slid by
0.125 (one master face) in one increment.  Expected: the block stays in contact (9 nodes,
normal reaction ~ -13) or the increment is cut back.  Observed: the increment converges in
a few iterations with 0 nodes in contact and a zero reaction -- the block has passed into
the foundation -- and nothing (cutback, warning) reports it.

Why: ``interaction._nearest_faces`` keeps the candidate faces whose centroid lies within
``radius`` = 2 x (largest node-to-centroid distance of a face) = one face length in 2D,
so each slave node gets only its own face and the nearer neighbour (2 candidates here).
A node in the trailing half of its face that moves forward by more than half a face
projects onto none of its candidates at the next re-pairing and is dropped
(``ContactInteraction.pair``); once every node is dropped the bodies are uncoupled, the
linear problem converges at once, and the solver has no test that rejects it.

    PYTHONPATH=. python benchmarks/stability/reproducers/lost_contact.py
"""
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))

from dolfinx_friction.api import run  # noqa: E402
from dolfinx_friction.model import BC, Body, ContactPair, Scene, Step  # noqa: E402
from tests.verification.test_stability import block_on_foundation  # noqa: E402

mesh = block_on_foundation(Path("/tmp/dfx_lost_contact.msh"))
for slide in (0.05, 0.125):  # 0.4 and 1.0 master face in one increment
    scene = Scene(
        mesh=mesh, bodies=(Body("block", 1000.0, 0.3), Body("foundation", 1000.0, 0.3)),
        contacts=(ContactPair("block_bottom", "foundation_top", mu=0.3),),
        steps=(Step("press", bcs=(BC("foundation_bottom", (0.0, 0.0)),
                                  BC("block_top", (0.0, -0.01)))),
               Step("slide", bcs=(BC("block_top", (slide, -0.01)),))))
    result = run(scene, write=False)
    for inc in result.increments:
        print(f"slide {slide}: {inc.step_name:5s} t = {inc.t:.3f}  {inc.iterations} iterations  "
              f"{inc.active} nodes in contact  R(block_top) = {inc.reactions['block_top'].round(3)}")
