"""The CalculiX comparison cases at finite strain, shared by the verification tests
(``tests/verification/test_calculix_nlgeom.py``, where their measured differences are) and
the benchmarks (``benchmarks/bench_ccx.py``, ``bench_ccx_nlgeom.py``): the scenes on the
meshes of :mod:`dolfinx_friction.reference.meshes`, the ironing's summary figures, and the
text of a block-on-a-foundation scene file for the command line's tests and benchmarks.
Dimensionless units."""
from __future__ import annotations

import numpy as np

from dolfinx_friction.scene.model import BC, Body, ContactPair, Output, Scene, Step

__all__ = ["E", "NU", "press_shear_scene", "ironing_scene", "ironing_figures",
           "block_on_foundation_toml"]

#: The block's Young's modulus and Poisson's ratio in the press and shear.
E, NU = 1000.0, 0.3


def press_shear_scene(mesh, block_model: str = "neo-hookean", depth: float = 0.3 * 0.25,
                      shear: float = 0.09, shear_increments: int = 6) -> Scene:
    """The block of :func:`~dolfinx_friction.reference.meshes.blocks_on_foundation`
    (E = 1000, nu = 0.3, ``block_model``) pressed by ``depth`` onto a linear foundation 100
    times stiffer, then its top moved sideways by ``shear``; mu = 0.3, stick slope 20 E."""
    return Scene(
        mesh=mesh,
        bodies=(Body("block", E, NU, model=block_model), Body("foundation", 100 * E, NU)),
        contacts=(ContactPair("block_bottom", "foundation_top", mu=0.3, K="calculix",
                              stick_slope=20 * E),),
        steps=(Step("press", increments=4, bcs=(BC("foundation_bottom", (0.0, 0.0, 0.0)),
                                                 BC("block_top", (0.0, 0.0, -depth)))),
               Step("shear", increments=shear_increments,
                    bcs=(BC("block_top", (shear, 0.0, -depth)),))),
        output=Output(reactions=("block_top", "foundation_bottom"), fields=False),
        title="Neo-Hookean block pressed by 30 % and sheared (CalculiX NLGEOM comparison)")


def ironing_scene(mesh, block_model: str = "neo-hookean", depth: float = 1.25,
                  drag: float = 1.5, press_increments: int = 4,
                  drag_increments: int = 12, dim: int = 3) -> Scene:
    """The plane-strain ironing on a mesh of :func:`~dolfinx_friction.reference.meshes.ironing`
    of dimension ``dim`` (3: one layer, ``u_z = 0`` on both faces): a soft block (E = 10,
    nu = 0.3, ``block_model``) indented by ``depth`` by a stiff linear die (E = 1e4), then
    dragged by ``drag``, mu = 0.3, CalculiX's penalty and stick slope."""
    def u(*c):
        return c + (0.0,) if dim == 3 else c

    plane = ((BC("block_faces", (None, None, 0.0)), BC("die_faces", (None, None, 0.0)))
             if dim == 3 else ())
    return Scene(
        mesh=mesh,
        bodies=(Body("block", 10.0, 0.3, model=block_model), Body("die", 1.0e4, 0.3)),
        contacts=(ContactPair("block_top", "die_surface", mu=0.3, K="calculix",
                              stick_slope="calculix"),),
        steps=(Step("press", increments=press_increments,
                    bcs=(BC("block_bottom", u(0.0, 0.0)),
                         BC("die_top", u(0.0, -depth))) + plane),
               Step("drag", increments=drag_increments,
                    bcs=(BC("die_top", u(drag, -depth)),))),
        output=Output(reactions=("die_top", "block_bottom"), fields=False),
        title=f"plane-strain ironing of a {block_model} block"
              + (", one hexahedron layer" if dim == 3 else "") + " (CalculiX NLGEOM comparison)")


def ironing_figures(reactions: dict, last: int = 4) -> dict:
    """``{(step, increment): (fx, fy, fz)}`` of the die -> end-of-indentation force
    ``|F_y|``, mean sliding force (mean F_x over the last ``last`` drag increments),
    friction ratio (that mean over the mean ``|F_y|``)."""
    press = max(k for k in reactions if k[0] == 0)
    drag = sorted(k for k in reactions if k[0] == 1)[-last:]
    fx = float(np.mean([reactions[k][0] for k in drag]))
    fy = float(np.mean([abs(reactions[k][1]) for k in drag]))
    return {"press": abs(float(reactions[press][1])), "slide": fx, "ratio": fx / fy}


def block_on_foundation_toml(mesh: str, *, title: str = "block slid on a foundation",
                             E: float = 1000.0, nu: float = 0.3, mu: float = 0.3,
                             press: float = -0.01, slide: float = 0.2,
                             slide_increments: int = 2, contact: str = "",
                             output: str = "fields = true") -> str:
    """The text of a scene file: the block of the mesh ``mesh`` (groups ``block``,
    ``foundation``, ``block_bottom``, ``block_top``, ``foundation_top``,
    ``foundation_bottom``, as :func:`~dolfinx_friction.reference.meshes.blocks_on_foundation`
    and the benchmarks' two boxes name them) pressed by ``press`` along z in one increment,
    then its top slid by ``slide`` along x in ``slide_increments``; ``contact`` adds lines to
    the ``[[contact]]`` table, ``output`` is the ``[output]`` table's body.  Lengths in the
    mesh's unit, E in its stress unit."""
    return f'''title = "{title}"
[mesh]
file = "{mesh}"
[[body]]
name = "block"
E = {E}
nu = {nu}
[[body]]
name = "foundation"
E = {E}
nu = {nu}
[[contact]]
slave = "block_bottom"
master = "foundation_top"
mu = {mu}
{contact}
[[step]]
name = "press"
  [[step.bc]]
  on = "foundation_bottom"
  u = [0.0, 0.0, 0.0]
  [[step.bc]]
  on = "block_top"
  u = [0.0, 0.0, {press}]
[[step]]
name = "slide"
increments = {slide_increments}
  [[step.bc]]
  on = "block_top"
  u = [{slide}, 0.0, {press}]
[output]
{output}
'''
