"""O-ring: a Neo-Hookean cord section squeezed between two rigid planes (axisymmetric).

The meridian section (r = x, z = y) of an O-ring of mean radius R = 5 and cord diameter
d = 2 (the half disk above its mid-plane, centre (5, 0), triangles of size 0.1; the
mid-plane y = 0 is a symmetry plane, u_z = 0).  A rigid plane starting tangent to the cord
at y = 1 moves down by 0.3 in 10 increments: the cord is squeezed by 30 % of its diameter
between it and its mirror image.  Compressible Neo-Hooke (E = 10, nu = 0.45), friction
mu = 0.2 on the plane.  Forces are per full revolution.

The script prints the force on the plane against the squeeze and, for orientation,
Lindley's empirical O-ring load per unit circumference ``E d (1.25 e^1.5 + 50 e^6)``
(e: relative squeeze; incompressible rubber, flat plates) times ``2 pi R``; and renders the
deformed section coloured by von Mises stress and by stick/slip.

    python demos/o_ring.py
"""
from __future__ import annotations

import math
from pathlib import Path

import _common as C  # noqa: F401  (pyvista before dolfinx)

from dolfinx_friction.reference import meshes

SCENE = C.HERE / "o_ring.toml"
MESH = C.HERE / "o_ring.msh"
R, D, E = 5.0, 2.0, 10.0


def build_mesh(path: Path, h: float = 0.1) -> None:
    """The half cord section (:func:`dolfinx_friction.reference.meshes.ring_section`),
    triangles of size ``h``."""
    meshes.ring_section(path, R, D / 2, h)


def lindley(squeeze: float) -> float:
    """Lindley's O-ring force for a whole ring squeezed by ``squeeze`` (a length)."""
    e = squeeze / D
    return 2 * math.pi * R * E * D * (1.25 * e ** 1.5 + 50 * e ** 6)


def main(argv=None) -> None:
    args, scene = C.command_line(__doc__, SCENE, argv)
    result = C.run_demo(args, scene, MESH, build_mesh)
    if not args.no_render:
        C.render(result, "o_ring_von_mises", warp=1.0, body_scalar="von_mises",
                 title="O-ring squeezed by 30 % (axisymmetric section, von Mises)",
                 contact_margin=0.3)
        C.render(result, "o_ring_status", scalar="status", warp=1.0,
                 title="O-ring squeezed by 30 %: stick / slip on the plane", contact_margin=0.3)
    if C.MPI.COMM_WORLD.rank != 0:
        return
    print(" incr  squeeze  force on the plane  Lindley (empirical)")
    for inc in result.increments:
        squeeze = 2 * 0.3 * inc.t  # both planes: twice the plane's travel
        F = abs(inc.rigid_f["gland"][1])
        print(f"{inc.increment:5d}  {squeeze:7.3f}  {F:18.3f}  {lindley(squeeze):19.3f}")


if __name__ == "__main__":
    main()
