"""The picture of one converged increment from the files a run wrote (``dolfinx-friction
render``): no solve, no dolfinx; the drawing is :func:`dolfinx_friction.viz.pictures.draw`'s, the
same as :func:`dolfinx_friction.viz.pictures.render` makes of a live problem.

What is read:

* ``history.csv``: the converged increments (the picture's step, increment and ``t``) and
  the translations ``U_<rigid>_*`` of the rigid obstacles;
* ``fields/step<s>_increment<iiii>/<body>.xdmf`` (+ ``.h5``), through VTK's XDMF reader:
  each body's mesh, ``displacement``, ``contact_pressure``, ``status`` and ``von_mises``;
* the scene named in ``summary.json`` (with its recorded ``overrides``), only for the
  shapes of the rigid obstacles; they are left out (with a logged warning) when it
  cannot be read.

The facet groups are not in the field files.  The slave contact surfaces are taken to be
the boundary facets whose corner nodes all carry a contact element (``status`` >= 0):
facets with a node beyond the master's reach (no element, ``status`` -1 like a node that
is no slave node) are drawn as plain body surface, not in the grey of open contact.  The
master surfaces outlined in the 3D close-up are the boundary facets of the bodies without
slave facets that face the slave surfaces.  Cells are drawn through their corner nodes, as
in the live picture.
"""
from __future__ import annotations

import logging
from pathlib import Path
from typing import Optional, Union

from dolfinx_friction.viz import pictures as viz  # noqa: I001  (pyvista before anything that may load dolfinx)
import numpy as np
import pyvista

from dolfinx_friction.io.files import atomic_path
from dolfinx_friction.io.reader import ResultsError, RunFiles, read_run
from dolfinx_friction.scene.model import Scene
from dolfinx_friction.scene.toml import SceneError, load_scene

__all__ = ["choose_increment", "field_folder", "render_files"]

logger = logging.getLogger(__name__)

#: Facets (edges in 2D, faces in 3D) of the linear VTK cells, as corner cycles; the
#: orientation of 3D faces is set outward from the cell's centroid.
_FACETS = {5: [[0, 1], [1, 2], [2, 0]],  # triangle
           9: [[0, 1], [1, 2], [2, 3], [3, 0]],  # quadrilateral
           10: [[0, 1, 2], [0, 1, 3], [1, 2, 3], [0, 2, 3]],  # tetrahedron
           12: [[0, 1, 2, 3], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6],
                [3, 0, 4, 7]]}  # hexahedron
_GDIM = {5: 2, 9: 2, 10: 3, 12: 3}


def choose_increment(run: RunFiles, increment: Optional[int]) -> int:
    """Row of ``history.csv`` (from 0) of the ``increment``-th converged increment, counted
    from 1 in history order (negative: from the end; None: the last)."""
    n = len(run.history)
    if n == 0:
        raise ResultsError(f"{run.directory}: no converged increment to draw")
    if increment is None:
        return n - 1
    if 1 <= increment <= n:
        return increment - 1
    if -n <= increment <= -1:
        return n + increment
    raise ResultsError(f"--increment {increment}: out of range: {run.directory} has {n} "
                       f"converged increment{'s' if n > 1 else ''} (1 to {n}, or -1 for the "
                       "last)")


def field_folder(run: RunFiles, row: int) -> Path:
    """``fields/step<s>_increment<iiii>`` of a row of ``history.csv``."""
    r = run.history[row]
    return run.directory / "fields" / f"step{int(r['step'])}_increment{int(r['increment']):04d}"


def _read_body(path: Path) -> pyvista.UnstructuredGrid:
    """A body's field file: one grid with all its point and cell arrays."""
    from vtkmodules.vtkCommonCore import vtkObject
    vtkObject.GlobalWarningDisplayOff()  # a bad file is reported below, in one line
    try:
        blocks = pyvista.read(path)
    except Exception as exc:  # VTK's reader fails in many ways: one line naming the file
        raise ResultsError(f"{path}: cannot be read: {exc}") from None
    finally:
        vtkObject.GlobalWarningDisplayOn()
    grids = [b for b in (blocks if isinstance(blocks, pyvista.MultiBlock) else [blocks])
             if b is not None and b.n_points]
    if not grids:
        raise ResultsError(f"{path}: cannot be read (no mesh in it)")
    grid = grids[0].copy()
    for other in grids[1:]:  # one grid per function, all on the same mesh
        for name in other.point_data.keys():
            grid.point_data[name] = other.point_data[name]
        for name in other.cell_data.keys():
            grid.cell_data[name] = other.cell_data[name]
    for name in ("displacement", "contact_pressure", "status"):
        if name not in grid.point_data:
            raise ResultsError(f"{path}: no {name} field in it")
    return grid


def _boundary_facets(cells: np.ndarray, kind: int, X: np.ndarray) -> np.ndarray:
    """(n, corners) nodes of the boundary facets of a mesh (facets of one cell only); 3D
    faces ordered with outward normals (from the centroid of their cell)."""
    local = np.array(_FACETS[kind])
    facets = cells[:, local].reshape(-1, local.shape[1])
    owner = np.repeat(np.arange(len(cells)), len(local))
    _, first, count = np.unique(np.sort(facets, axis=1), axis=0, return_index=True,
                                return_counts=True)
    keep = first[count == 1]
    facets, owner = facets[keep], owner[keep]
    if _GDIM[kind] == 3:
        normal = np.cross(X[facets[:, 1]] - X[facets[:, 0]], X[facets[:, -1]] - X[facets[:, 0]])
        outward = X[facets].mean(axis=1) - X[cells[owner]].mean(axis=1)
        inward = np.einsum("ij,ij->i", normal, outward) < 0
        facets[inward] = facets[inward, ::-1]
    return facets


def _body_data(name: str, grid: pyvista.UnstructuredGrid, warp: float, amplify: str
               ) -> tuple[int, dict, Optional[dict], Optional[dict]]:
    """``(gdim, body, slave facets, other boundary facets)`` of one body, as
    :func:`viz.draw` takes them (facets None when there are none).  Slave facets: those
    whose corner nodes all carry a contact element (``status`` >= 0)."""
    topology, cell_types = viz.linear_cells(np.asarray(grid.cells), np.asarray(grid.celltypes))
    kind = int(cell_types[0])
    if kind not in _FACETS or (cell_types != kind).any():
        raise ResultsError(f"{name}: cells of VTK type {sorted(set(cell_types.tolist()))} "
                           "cannot be drawn (triangles, quadrilaterals, tetrahedra or "
                           "hexahedra of one type per body)")
    X = np.asarray(grid.points, dtype=float)
    u = np.asarray(grid.point_data["displacement"], dtype=float).reshape(len(X), -1)
    mean = u.mean(axis=0) if amplify == "deformation" else np.zeros(3)
    x = X + mean + warp * (u - mean)
    von_mises = grid.cell_data.get("von_mises")
    body = dict(name=name, topology=topology, cell_types=cell_types, x=x,
                von_mises=None if von_mises is None else np.asarray(von_mises).ravel())
    status = np.rint(np.asarray(grid.point_data["status"])).astype(int).ravel()
    facets = _boundary_facets(topology.reshape(len(cell_types), -1)[:, 1:], kind, X)
    slave = (status[facets] >= 0).all(axis=1)
    pressure = np.asarray(grid.point_data["contact_pressure"], dtype=float).ravel()
    s, m = facets[slave], facets[~slave]
    slaves = dict(body=name, group=f"{name} contact surface", x=x[s], pressure=pressure[s],
                  status=status[s], X=X[s]) if len(s) else None
    others = dict(body=name, group=f"{name} boundary", x=x[m]) if len(m) else None
    return _GDIM[kind], body, slaves, others


def _facing(others: list[dict], slaves: list[dict]) -> list[dict]:
    """The boundary facets (3D) that face the slave surfaces (outward normal within 60
    degrees of minus their mean normal): the master surfaces, outlined in the close-up."""
    n = viz.mean_normal(slaves)
    out = []
    for facets in others:
        x = facets["x"]
        m = np.cross(x[:, 1] - x[:, 0], x[:, -1] - x[:, 0])
        facing = m @ n < -0.5 * np.linalg.norm(m, axis=1)
        if facing.any():
            out.append(dict(facets, x=x[facing]))
    return out


def _scene(run: RunFiles, rigid: bool) -> Optional[Scene]:
    """The scene of the run (``summary.json``'s ``scene`` with its ``overrides``), or None;
    a warning when it is needed for the rigid obstacles (``rigid``) and cannot be read."""
    summary = run.summary or {}
    source, overrides = summary.get("scene"), summary.get("overrides") or []
    if isinstance(overrides, dict):
        overrides = [f"{key}={value}" for key, value in overrides.items()]
    try:
        if not source:
            raise SceneError("no summary.json naming the scene")
        return load_scene(Path(source), [str(o) for o in overrides])
    except SceneError as exc:
        if rigid:
            logger.warning("rigid obstacles not drawn: %s", exc)
        return None


def _rigids(scene: Optional[Scene], row: dict, gdim: int, warp: float) -> list[dict]:
    """The rigid obstacles of the scene, translated as the history row says and turned as the
    scene's steps turn them at the row's time."""
    out = []
    for rigid in scene.rigids if scene is not None else ():
        try:
            U = [float(row[f"U_{rigid.name}_{a}"]) for a in "xyz"[:gdim]]
            step = int(row["step"])
            rotation = scene.rotation_at(rigid.name, step, float(row["t"]) - step)
        except (KeyError, ValueError, IndexError):
            continue
        out.append(dict(rigid=viz.turned(rigid, None if rotation is None
                                         else warp * np.asarray(rotation)),
                        U=warp * np.pad(U, (0, 3 - gdim))))
    return out


def render_files(directory: Union[str, Path], png_path: Union[str, Path, None] = None,
                 increment: Optional[int] = None, scalar: str = "contact_pressure",
                 warp: float = 1.0, amplify: str = "total", body_scalar: Optional[str] = None
                 ) -> tuple[Path, RunFiles, int]:
    """Draw one converged increment of the results in ``directory`` into ``png_path``
    (default ``directory/render_step<s>_increment<iiii>.png``), written whole or not at all.

    ``increment``: as :func:`choose_increment`; ``scalar``, ``warp`` (displacement scale),
    ``amplify`` and ``body_scalar``: as :func:`dolfinx_friction.viz.pictures.render` (the mean
    translation of a body is the mean displacement of its nodes).  Returns the path, the
    results read and the row of ``history.csv`` drawn.  Raises :class:`ResultsError`.
    """
    run = read_run(directory)
    k = choose_increment(run, increment)
    folder = field_folder(run, k)
    files = sorted(folder.glob("*.xdmf")) if folder.is_dir() else []
    if not files:
        raise ResultsError(f"{folder}: no field files (a run with output.fields = false "
                           "cannot be rendered)")
    scene = _scene(run, rigid=any(c.startswith("U_") for c in run.header))
    order = {b.name: n for n, b in enumerate(scene.bodies)} if scene is not None else {}
    files.sort(key=lambda f: order.get(f.stem, len(order)))  # the colours of the live picture
    gdims, bodies, slaves, others = set(), [], [], []
    for path in files:
        gdim, body, slave, other = _body_data(path.stem, _read_body(path), warp, amplify)
        if body_scalar == "von_mises" and body["von_mises"] is None:
            raise ResultsError(f"{path}: no von_mises field in it")
        gdims.add(gdim)
        bodies.append(body)
        slaves += [slave] if slave is not None else []
        others += [other] if other is not None and slave is None else []
    gdim = max(gdims)
    row = run.history[k]
    data = dict(bodies=bodies, slaves=slaves,
                masters=_facing(others, slaves) if gdim == 3 and slaves else [],
                rigids=_rigids(scene, row, gdim, warp if amplify == "total" else 1.0))
    steps = (run.summary or {}).get("steps") or []
    step = int(row["step"])
    name = f" ({steps[step]})" if step < len(steps) else ""
    title = (f"{run.title()}\nstep {step}{name}, increment {int(row['increment'])}, "
             f"t = {float(row['t']):.4g}")
    png_path = Path(png_path) if png_path is not None else \
        run.directory / f"{folder.name.replace('step', 'render_step', 1)}.png"
    png_path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(png_path) as partial:
        viz.draw(data, gdim, partial, scalar=scalar, warp=warp, amplify=amplify, title=title,
                 body_scalar=body_scalar)
    return png_path, run, k
