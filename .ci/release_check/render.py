"""Solve a scene and render it with dolfinx_friction.viz.pictures (a smoke test of the pyvista path).

    python3 render.py SCENE.toml OUT_DIR

Run under ``xvfb-run`` where VTK has no off-screen (EGL/OSMesa) window, as with
Debian 13's python3-vtk9.  Exits 1 when no picture was written.
"""
import sys
from pathlib import Path

from dolfinx_friction.viz import pictures as viz  # noqa: I001  (pyvista before dolfinx)
from dolfinx_friction.scene.runner import run

scene, out = Path(sys.argv[1]), Path(sys.argv[2])
result = run(scene, out=out)
png = viz.render(result, out / "release_check.png")
if png is None or not Path(png).is_file() or Path(png).stat().st_size == 0:
    print(f"render.py: no picture written ({png})", file=sys.stderr)
    raise SystemExit(1)
print(f"render.py: {png} ({Path(png).stat().st_size} bytes)")
