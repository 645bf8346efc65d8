"""Ironing at finite strain: a stiff indenter pressed 15 % into a soft Neo-Hookean block and
dragged along it (2D plane strain, mu = 0.3), against the small-strain answer on the same mesh.

The mesh and the indenter are those of ``demos/ironing.py`` (block 20 x 5, E = 10, the half
disk 1000 times stiffer); the block is Neo-Hookean (CalculiX's NEO HOOKE), indented by 0.75
(15 % of its height) and dragged by 7, so that the indenter crosses 42 of the block's top
faces.  The same scene is run with ``model = "linear"``; the chart
``ironing_neo_hookean_forces.png`` shows both force histories of the indenter, the pictures
``ironing_neo_hookean_status.png`` and ``ironing_neo_hookean_von_mises.png`` the deformed
block at the end (stick / slip on its top; coloured by von Mises stress).

    python demos/ironing_neo_hookean.py
    python -m dolfinx_friction run demos/ironing_neo_hookean.toml
"""
from __future__ import annotations

import _common as C  # noqa: F401  (pyvista before dolfinx)
import ironing
import numpy as np

SCENE = C.HERE / "ironing_neo_hookean.toml"


def forces(result) -> np.ndarray:
    """(increments, 3): pseudo-time, |R_y| and |R_x| / |R_y| of the indenter."""
    rows = [(inc.t, abs(inc.reactions["die_top"][1]),
             abs(inc.reactions["die_top"][0]) / abs(inc.reactions["die_top"][1]))
            for inc in result.increments]
    return np.array(rows)


def main(argv=None) -> None:
    args, scene = C.command_line(__doc__, SCENE, argv)
    finite = C.run_demo(args, scene, ironing.MESH, ironing.build_mesh)
    args.set = list(args.set) + ["body.0.model=linear"]
    args.out = str(C.HERE / "ironing_neo_hookean_linear_results")
    small = C.run_scene(scene, args)[0]
    a, b = forces(finite), forces(small)
    press = [i for i, inc in enumerate(finite.increments) if inc.step_name == "press"][-1]
    drag = slice(press + 1 + (len(a) - press - 1) // 4, None)  # the steady part of the drag
    C.root_print(f"end of indentation: |R_y| {a[press, 1]:.4f} (finite strain) vs "
                 f"{b[press, 1]:.4f} (small strain): {a[press, 1] / b[press, 1] - 1:+.1%}")
    C.root_print(f"steady drag: mean |R_y| {a[drag, 1].mean():.4f} vs {b[drag, 1].mean():.4f}, "
                 f"friction ratio {a[drag, 2].mean():.4f} vs {b[drag, 2].mean():.4f} (mu = 0.3)")
    if args.no_render:
        return
    C.render(finite, "ironing_neo_hookean_status", scalar="status", warp=1.0,
             contact_margin=1.0, title="Neo-Hookean block ironed by a stiff die, mu = 0.3")
    C.render(finite, "ironing_neo_hookean_von_mises", scalar="status", warp=1.0,
             contact_margin=1.0, body_scalar="von_mises",
             title="von Mises stress of the Neo-Hookean block, stick / slip on its top")
    if C.MPI.COMM_WORLD.rank == 0:
        plt = C.pyplot()
        fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
        for data, label in ((a, "Neo-Hookean"), (b, "small strain, same mesh")):
            top.plot(data[:, 0], data[:, 1], label=label)
            bottom.plot(data[:, 0], data[:, 2], label=label)
        top.set_ylabel("indenter force |R_y|")
        bottom.set_ylabel("|R_x| / |R_y|")
        bottom.axhline(0.3, color="grey", lw=0.8, ls="--")
        bottom.set_xlabel("pseudo-time (0-1 press, 1-2 drag)")
        top.legend()
        C.save_figure(fig, finite, "ironing_neo_hookean_forces")


if __name__ == "__main__":
    main()
