"""Scene-format version 2: ``[[body]] model``, read, refused where it cannot apply, and run.

Bad input gets one line naming the key (unknown model, listing the models; ``model`` on a
rigid obstacle; plane stress at finite strain).  A ``pressure`` on a finite-strain body
follows the deformed face: a Neo-Hookean block squeezed by a top pressure onto a
frictionless plane carries ``p`` times its *current* width, a dead traction of the same
size carries ``p`` times the reference width.
"""
from __future__ import annotations

import pytest
from scipy.optimize import brentq

from dolfinx_friction.scene.runner import run
from dolfinx_friction.scene.model import BC, Body, ContactPair, Load, Rigid, Scene, Step
from dolfinx_friction.reference.compare import contact_state
from dolfinx_friction.scene.toml import SceneError, parse_scene
from dolfinx_friction.reference import meshes
from tests.cli.test_scene import edited, put
from tests.verification.test_finite_strain import E, NU, nominal_stress


def test_model_is_read():
    data = edited("rigid2d", put("body.0.model", "neo-hookean"), put("body.0.plane", "strain"))
    assert parse_scene(data).bodies[0].model == "neo-hookean"
    assert parse_scene(edited("rigid2d")).bodies[0].model == "linear"


@pytest.mark.parametrize("edit, fragments", [
    (put("body.0.model", "mooney-rivlin"), ["body.0.model", "must be one of", "neo-hookean",
                                            "saint-venant-kirchhoff", "linear"]),
    (put("body.0.model", "neo-hooke"), ["body.0.model", "did you mean 'neo-hookean'"]),
    (put("rigid.0.model", "neo-hookean"), ["rigid.0.model"]),
    (lambda d: (put("body.0.model", "saint-venant-kirchhoff")(d), put("body.0.plane", "stress")(d)),
     ["body.0.plane", "plane stress is not available at finite strain"]),
    (put("body.0.nu", 0.5), ["body.0.nu"]),
])
def test_bad_model_gets_one_line(edit, fragments):
    with pytest.raises(SceneError) as caught:
        parse_scene(edited("rigid2d", edit))
    message = str(caught.value)
    assert "\n" not in message
    for fragment in fragments:
        assert fragment in message, message


@pytest.mark.parametrize("follower", [True, False])
def test_pressure_follows_the_deformed_face(shared_dir, follower):
    """Top pressure p = 150 on a 1 x 0.25 Neo-Hookean block (left roller) on a frictionless
    plane: homogeneous, the lateral stretch grows, and the plane carries p x the current
    width (follower) or p x the reference width (a dead traction)."""
    mesh = meshes.rectangle_2d(shared_dir / "rect.msh", n=(4, 2))
    p = 150.0
    load = Load("top", pressure=p) if follower else Load("top", traction=(0.0, -p))
    scene = Scene(
        mesh=mesh, bodies=(Body("block", E, NU, model="neo-hookean"),),
        rigids=(Rigid("floor", "plane", point=(0.0, 0.0), normal=(0.0, 1.0)),),
        contacts=(ContactPair("bottom", "floor", K=2000 * E),),
        steps=(Step("squeeze", increments=4, bcs=(BC("left", (0.0, None)),), loads=(load,)),))
    result = run(scene, write=False)
    state = contact_state(result)
    carried = state["normal_force"].sum()
    # the homogeneous state: lateral stretch a, axial b with P_11 = 0 and P_22 = -p a (or -p)
    def residual(a):
        b = brentq(lambda b: nominal_stress("neo-hookean", [a, b, 1.0], 1)
                   + p * (a if follower else 1.0), 0.2, 1.0)
        return nominal_stress("neo-hookean", [a, b, 1.0], 0)
    lateral = brentq(residual, 1.0, 2.0)
    expected = p * (lateral if follower else 1.0)
    print(f"\n{'follower' if follower else 'dead'}: carried {carried:.12g}, expected "
          f"{expected:.12g} (lateral stretch {lateral:.5f})")
    assert lateral > 1.04  # the current width differs from the reference one by 5 %
    assert carried == pytest.approx(expected, rel=1e-9)


def test_overrides_with_a_scene_object_are_refused():
    """``--set``-style overrides act on a scene file; given with a Scene object they would
    be ignored, so they are an input error naming ``overrides``."""
    scene = parse_scene({"mesh": {"file": "m.msh"}, "body": [{"name": "b", "E": 1.0, "nu": 0.3}],
                         "step": [{"bc": [{"on": "g", "u": [0.0, 0.0]}]}]})
    with pytest.raises(SceneError, match="overrides apply to a scene file") as info:
        run(scene, overrides=["body.0.E=2.0"], write=False)
    assert info.value.key == "overrides"
