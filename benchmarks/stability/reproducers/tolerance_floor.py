"""Reproducer: Newton 'fails' on iterates that have converged to round-off.

Fixed in a68a938 (round-off floor ``system.ROUNDOFF_FLOOR`` times |K_bulk| |u| + |f_ext| +
the contact terms; pinned by ``test_soft_penalty_converges_at_roundoff``).  Now every
increment converges, most at 3e-9 .. 1e-8, above what rtol and atol ask (1e-10) and below
the floor, which this script prints.  What follows describes the solver before that commit.

The stopping test is ``|R| <= max(rtol * |R_0|, atol)`` with ``R_0`` the first residual of
the increment, rtol = 1e-9 and an absolute atol = 1e-10.  When the increment changes
little (a soft penalty; small increments; and every cutback makes ``R_0`` smaller still)
``rtol * R_0`` falls below the round-off floor of the residual, about
1e-16 x cond x |internal forces|, and so does ``atol`` whenever the forces are large
(E = 210000 here).  The residual then stagnates at the floor for 30 iterations, the
increment is cut back (smaller ``R_0``: worse) and the run stops with ConvergenceError.

The 3D sliding block demo (coarse: 3 x 3 block faces on 6 x 3 foundation faces) with a
soft penalty K = 0.01 E/h (315) and 10 slide increments: the residual drops from 0.18
to 3.6e-9 in one iteration and stays at 1e-9..3e-9; required: 1.8e-10.  The maps show
the same stall for the ironing demo at K >= 1e3 E/h (last residual 1.1e-10 against
atol 1e-10; whether a given increment passes is decided by round-off) and for the Hertz
cylinder at K = 1e4 E/h.

    PYTHONPATH=. python benchmarks/stability/reproducers/tolerance_floor.py
"""
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

import _scenes  # noqa: E402
from dolfinx_friction.scene.build import ContactProblem  # noqa: E402
from dolfinx_friction.scene.driver import ConvergenceError, Solver  # noqa: E402

scene, _ = _scenes.block3d_scene({"k": 0.01, "increments": 10})
problem = ContactProblem(scene)
solver = Solver(problem)


def show(inc):
    r = inc.residuals
    step = scene.steps[inc.step]
    print(f"t = {inc.t:.4f}: residuals {' '.join(f'{x:.1e}' for x in r[:6])}"
          f"{' ...' if len(r) > 6 else ''} (tolerances ask "
          f"{max(step.newton_rtol * r[0], step.newton_atol):.1e}, round-off floor "
          f"{problem.system.roundoff_floor():.1e})")


try:
    solver.run(show)
except ConvergenceError as exc:
    print("ConvergenceError:", exc)
