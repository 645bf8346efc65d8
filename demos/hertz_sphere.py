"""Hertz point contact: an elastic sphere pressed onto a rigid plane or an elastic block (3D).

One eighth of a sphere (radius R = 10, centre (0, 0, R), the part with
x, y >= 0 and z <= R) with symmetry conditions on x = 0 and y = 0 (the normal
component fixed, the others ``"free"``).  Its flat top (z = R) is pushed down
in 4 increments; tetrahedra, refined around the pole.  E = 1000, nu = 0.3,
frictionless.

* ``hertz_sphere.toml``: on a rigid plane z = 0 (``[[rigid]]``), approach 0.15;
* ``hertz_sphere_block.toml``: on a quarter block (20 x 20 x 10, same
  material, symmetry on x = 0, y = 0, bottom fixed), approach 0.3.

Reference (Johnson §4.2, :func:`dolfinx_friction.reference.analytic.hertz_sphere`): with
the total force ``F = 4 |R_top_z|``, ``a = (3 F R / (4 E*))^(1/3)`` and
``p0 = 3 F / (2 pi a^2)``; ``1/E* = (1-nu^2)/E`` on the rigid plane and
``2 (1-nu^2)/E`` on the block.  The script prints the largest nodal pressure
and a fit of ``p^2 = p0^2 (1 - r^2/a^2)`` against Hertz, and plots p(r).

    python demos/hertz_sphere.py                       # rigid plane
    python demos/hertz_sphere.py --scene demos/hertz_sphere_block.toml
"""
from __future__ import annotations

from pathlib import Path

import _common as C  # noqa: F401  (pyvista before dolfinx)
from demos import _meshing as G  # gmsh helpers, after _common (it puts the root on sys.path)
import numpy as np

from dolfinx_friction.reference.analytic import (effective_modulus, fit_elliptic, hertz_sphere,
                                       hertz_sphere_pressure)

SCENE = C.HERE / "hertz_sphere.toml"
# scene -> (mesh, build_mesh arguments)
MESHES = {"hertz_sphere.toml": (C.HERE / "hertz_sphere.msh",
                                dict(with_block=False, h_contact=0.12)),
          "hertz_sphere_block.toml": (C.HERE / "hertz_sphere_block.msh",
                                      dict(with_block=True, h_contact=0.15))}
R, E, NU = 10.0, 1000.0, 0.3
BLOCK = (20.0, 10.0)  # quarter-block side, depth


def build_mesh(path: Path, with_block: bool = False, h_contact: float = 0.15,
               h_far: float = 3.0, master_ratio: float = 2.0,
               refine_radius: float = 1.8, order: int = 1) -> None:
    """Eighth of a sphere (and optionally a quarter block under it), refined tetrahedra.

    ``h_contact``: sphere element size within ``refine_radius`` of the pole
    (the block's is ``master_ratio`` times larger); ``h_far``: size far away;
    ``order``: geometric order (2: mid-edge nodes on the sphere, for ``degree = 2``).
    """
    with G.gmsh_model("hertz_sphere") as gmsh:
        occ = gmsh.model.occ
        ball = occ.addSphere(0, 0, R, R)
        box = occ.addBox(0, 0, 0, R, R, R)
        (sphere_dim_tag,), _ = occ.intersect([(3, ball)], [(3, box)])
        sphere = sphere_dim_tag[1]
        block = None
        if with_block:
            L, D = BLOCK
            block = occ.addBox(0, 0, -D, L, L, D)  # not fragmented: no shared nodes
        occ.synchronize()

        def faces(vol):
            out = {}
            for _, s in gmsh.model.getBoundary([(3, vol)], oriented=False):
                com = np.array(occ.getCenterOfMass(2, s))
                out[s] = com
            return out

        group = G.physical_group
        sphere_faces = faces(sphere)
        sym_x = [s for s, c in sphere_faces.items() if abs(c[0]) < 1e-6]
        sym_y = [s for s, c in sphere_faces.items() if abs(c[1]) < 1e-6]
        top = [s for s, c in sphere_faces.items() if abs(c[2] - R) < 1e-6]
        curved = [s for s in sphere_faces if s not in sym_x + sym_y + top]
        group(3, [sphere], "sphere")
        group(2, curved, "sphere_surface")
        group(2, top, "sphere_top")
        group(2, sym_x, "sphere_symmetry_x")
        group(2, sym_y, "sphere_symmetry_y")
        eps = 1e-6
        poles = [t for _, t in gmsh.model.getEntitiesInBoundingBox(-eps, -eps, -eps, eps, eps,
                                                                   eps, 0)]
        sphere_pole = [p for p in poles if p in {t for _, t in gmsh.model.getBoundary(
            [(3, sphere)], combined=False, recursive=True)}]
        refine = [(sphere_pole, h_contact, (3, sphere))]
        if block is not None:
            block_faces = faces(block)
            L, D = BLOCK
            group(3, [block], "block")
            group(2, [s for s, c in block_faces.items() if abs(c[2]) < 1e-6], "block_top")
            group(2, [s for s, c in block_faces.items() if abs(c[2] + D) < 1e-6], "block_bottom")
            group(2, [s for s, c in block_faces.items() if abs(c[0]) < 1e-6],
                  "block_symmetry_x")
            group(2, [s for s, c in block_faces.items() if abs(c[1]) < 1e-6],
                  "block_symmetry_y")
            block_corner = [p for p in poles if p not in sphere_pole]
            refine.append((block_corner, master_ratio * h_contact, (3, block)))

        # size h up to refine_radius from the pole (the block's corner), h_far 10 further out
        G.size_field(refine, h_far, refine_radius, refine_radius + 10.0)
        gmsh.option.setNumber("Mesh.Algorithm", 6)
        gmsh.option.setNumber("Mesh.Algorithm3D", 1)
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(order)
        G.write_msh(path, binary=True)


def quadratic(overrides: list[str]) -> bool:
    """Whether ``--set`` asks for quadratic bodies (``body.N.degree=2``)."""
    return any(o.replace(" ", "").startswith("body.") and o.replace(" ", "").endswith(
        ".degree=2") for o in overrides)


def main(argv=None) -> None:
    args, scene = C.command_line(__doc__, SCENE, argv)
    mesh, resolution = MESHES.get(scene.name, MESHES["hertz_sphere.toml"])
    if quadratic(args.set):  # P2 wants the mid-side nodes on the sphere, not on its chords
        mesh, resolution = mesh.with_name(f"{mesh.stem}_order2.msh"), {**resolution, "order": 2}
        args.set = [*args.set, f'mesh.file="{mesh}"']
    with_block = resolution["with_block"]
    result = C.run_demo(args, scene, mesh, build_mesh, **resolution)
    name = scene.stem
    what = "an elastic block" if with_block else "a rigid plane"
    if not args.no_render:
        C.render(result, name, warp=5.0, title=f"Hertz: sphere on {what} (1/8 model)",
                 contact_margin=0.3, view=(-1.0, -1.4, 0.8))  # onto the symmetry planes
    st = C.contact_state(result)
    if C.MPI.COMM_WORLD.rank != 0:
        return
    F = 4.0 * abs(result.increments[-1].reactions["sphere_top"][2])
    E_star = effective_modulus(E, NU, E, NU) if with_block else effective_modulus(E, NU)
    a, p0, delta = hertz_sphere(F, R, E_star)
    closed = st["status"] != 0
    r = np.linalg.norm(st["X"][closed, :2], axis=1)
    p = st["pressure"][closed]
    order = np.argsort(r)
    r, p = r[order], p[order]
    a_fit, p0_fit = fit_elliptic(r, p)
    r_all = np.linalg.norm(st["X_all"][:, :2], axis=1)
    # how well the lumped nodal areas integrate the Hertz pressure (edge effect of F_N/A_p)
    lumped = 4.0 * np.sum(st["area"][closed][order] * hertz_sphere_pressure(r, F, R, E_star)) / F
    outside = r_all[r_all > r.max()]
    print(f"sphere on {what}: total force F = {F:.4f} (4 x sphere_top reaction), "
          f"E* = {E_star:.3f}, {closed.sum()} nodes in contact")
    print(f"Hertz:   a = {a:.4f}   p0 = {p0:.4f}   approach {delta:.4f}")
    print(f"nodal:   p_max = {p.max():.4f} ({C.relerr(p.max(), p0)}) at r = {r[np.argmax(p)]:.4f};"
          f" last closed node at r = {r.max():.4f}, next slave node at "
          f"r = {outside.min() if len(outside) else np.nan:.4f}")
    print(f"fitted:  a = {a_fit:.4f} ({C.relerr(a_fit, a)})   p0 = {p0_fit:.4f} "
          f"({C.relerr(p0_fit, p0)})   [p^2 = p0^2 (1 - r^2/a^2) on "
          f"{int((p > 0.2 * p.max()).sum())} nodes]")
    print(f"lumping: 4 sum A_p p_Hertz(r_p) / F = {lumped:.4f} (nodal pressures carrying F exceed "
          f"Hertz by ~{100 * (1 / lumped - 1):.1f} % on average from this alone)")
    if not args.no_render:  # nodal pressures against Hertz
        rs = np.linspace(0, 1.6 * a, 400)
        C.profile_plot(result, f"{name}_profile", r, p,
                       (rs, hertz_sphere_pressure(rs, F, R, E_star),
                        f"Hertz: a = {a:.4f}, p0 = {p0:.3f}"), a_fit,
                       "r (distance from the axis)", f"Hertz: sphere on {what}", ms=3)


if __name__ == "__main__":
    main()
