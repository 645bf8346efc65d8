"""Off-screen pictures of a solved contact problem (pyvista).

:func:`render` draws the deformed bodies (displacements scaled by ``warp``),
the slave contact surfaces coloured by the nodal contact pressure
(``F_N / A_p``) or by the stick/slip status, the analytic rigid obstacles
translated by their current displacement, and a scalar bar, into a PNG.

Two panels by default:

* **overview**: every body and obstacle; 2D meshes are seen along ``-z``
  (parallel projection), 3D meshes isometrically;
* **contact**: a close-up of the closed contact zone; in 3D the slave
  surface is seen from the master side (through the master body, which is
  left out) so that the contact patch is visible.

Import order: VTK aborts with ``std::bad_alloc`` if it is loaded after
dolfinx in the same process.  Import this module (or ``pyvista``) *before*
``dolfinx`` or ``dolfinx_friction.scene.runner``; this module imports pyvista at import
time and dolfinx only inside functions.  Rendering is off-screen (without an X server
through VTK's EGL window, ``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow``, set at import
unless it is set already or ``DISPLAY`` is).

:func:`draw` makes the same picture from plain arrays: ``dolfinx-friction render``
(:mod:`dolfinx_friction.viz.snapshot`) feeds it from the files that a run wrote.

Parallel runs: :func:`render` is collective.  Every rank extracts its local
cells and slave facets (ghost values are updated first, so nodes shared by
two ranks carry the same values); the pieces are gathered to rank 0, which
renders the whole picture.  Other ranks return ``None``.  Nodes on partition
boundaries appear twice, which does not show.

Cells are built on the dofs (``dolfinx.plot.create_vtk_mesh(V)``; renamed
``vtk_mesh`` in dolfinx 0.9); higher-degree cells and contact faces are drawn
through their corner nodes only (P1 interpolation of the displacement).
"""
from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import Optional, Sequence, Union

if "DISPLAY" not in os.environ:  # off-screen pictures without an X server (VTK's own EGL)
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np  # noqa: E402
import pyvista  # noqa: E402

from dolfinx_friction.contact.element import OPEN, SLIP, STICK  # noqa: E402

pyvista.OFF_SCREEN = True

#: Colours of the bodies (cycled) and of the rigid obstacles.
BODY_COLORS = ("#c9d6e3", "#e8dcc4", "#d5e8d4", "#e6d0de", "#f5e6b8")
RIGID_COLOR = "#5a5a5a"
#: Status colours: open (and no element), stick, slip.
STATUS_COLORS = ("#b0b0b0", "#1f77b4", "#d62728")
# corner nodes of each face type in cyclic order (face-type node numbering)
_CORNERS = {"L2": [0, 1], "L3": [0, 1], "T3": [0, 1, 2], "T6": [0, 1, 2],
            "Q4": [0, 1, 3, 2], "Q9": [0, 1, 3, 2]}


# ------------------------------------------------------------------ dolfinx
def vtk_mesh(V):
    """``(topology, cell_types, x)`` of a Lagrange space: dolfinx 0.5 ``create_vtk_mesh``,
    renamed ``vtk_mesh`` in dolfinx 0.9."""
    from dolfinx_friction import _compat as compat  # imports dolfinx: after pyvista
    return compat.vtk_mesh(V)


# VTK higher-order cell types -> (linear type, number of corners); corners come first
_LINEAR = {69: (5, 3), 70: (9, 4), 71: (10, 4), 72: (12, 8),  # Lagrange cells
           22: (5, 3), 23: (9, 4), 28: (9, 4), 24: (10, 4), 25: (12, 8), 29: (12, 8)}


def linear_cells(topology: np.ndarray, cell_types: np.ndarray):
    """Corner-only (P1) cells of a higher-order VTK cell array (one cell type per mesh)."""
    topology, cell_types = np.asarray(topology), np.asarray(cell_types)
    if len(cell_types) == 0 or int(cell_types[0]) not in _LINEAR:
        return topology, cell_types
    kind, nc = _LINEAR[int(cell_types[0])]
    cells = topology.reshape(len(cell_types), -1)[:, 1:1 + nc]
    out = np.hstack([np.full((len(cells), 1), nc), cells]).ravel()
    return out, np.full(len(cells), kind, dtype=cell_types.dtype)


def _problem_of(result):
    """The ContactProblem of a RunResult, or the problem itself."""
    return getattr(result, "problem", result)


def _nodal_contact(problem, field) -> np.ndarray:
    """(n_local_nodes, 2): ``contact_pressure`` and ``status`` of the body's nodal contact
    fields (:mod:`~dolfinx_friction.fem.contact_fields`), ghost nodes from their owners."""
    from dolfinx_friction import _compat as compat

    fields = problem.contact_fields(field)
    f = compat.function(field.V)  # (gdim >= 2 components: room for both)
    a = f.x.array.reshape(-1, problem.gdim)
    a[:] = 0.0
    a[:, 0], a[:, 1] = fields["contact_pressure"][:, 0], fields["status"][:, 0]
    compat.scatter_forward(f)
    return f.x.array.reshape(-1, problem.gdim)[:, :2].copy()


def _facets(field, group: str) -> tuple[str, np.ndarray]:
    """Face type name and (n, corners) local nodes of a facet group, normals outward."""
    from dolfinx_friction.fem.surfaces import facet_nodes
    _, facets = field.mesh.groups[group]
    face, nodes = facet_nodes(field, facets)
    return face.name, nodes[:, _CORNERS[face.name]]


def _pad3(x: np.ndarray) -> np.ndarray:
    out = np.zeros((len(x), 3))
    out[:, : x.shape[1]] = x
    return out


def _cell_von_mises(field) -> np.ndarray:
    """The von Mises stress at the midpoint of every local cell (owned and ghost)."""
    from dolfinx_friction import _compat as compat
    from dolfinx_friction.scene.build import cauchy_stress, von_mises
    mesh = field.V.mesh
    expression = compat.quadrature_expression(von_mises(cauchy_stress(field)), mesh, 0)
    im = mesh.topology.index_map(mesh.topology.dim)
    cells = np.arange(im.size_local + im.num_ghosts, dtype=np.int32)
    return compat.evaluate_on_cells(expression, mesh, cells).reshape(len(cells), -1)[:, 0]


def _local_pieces(problem, warp: float, amplify: str) -> dict:
    """Everything this rank contributes to the picture, as plain arrays."""
    from mpi4py import MPI
    problem.system.scatter()
    d = problem.gdim
    bodies, slaves, masters = [], [], []
    slave_groups = {c.slave for c in problem.scene.contacts}
    master_groups = {c.master for c in problem.scene.contacts
                     if problem.scene.rigid(c.master) is None}
    for field in problem.fields:
        topology, cell_types = linear_cells(*vtk_mesh(field.V)[:2])
        u = field.u.x.array.reshape(-1, d)
        if amplify == "deformation":  # scale only what differs from the mean translation
            owned = u[: field.n_owned]
            total = problem.comm.allreduce(owned.sum(axis=0), op=MPI.SUM)
            count = problem.comm.allreduce(len(owned), op=MPI.SUM)
            mean = total / max(count, 1)
            x = _pad3(field.X + mean + warp * (u - mean))
        else:
            x = _pad3(field.X + warp * u)
        values = _nodal_contact(problem, field)
        bodies.append(dict(name=field.body.name, topology=np.asarray(topology),
                           cell_types=np.asarray(cell_types), x=x,
                           von_mises=_cell_von_mises(field)))
        for group in sorted(slave_groups):
            if field.mesh.groups.get(group) is None:
                continue
            _, corners = _facets(field, group)
            slaves.append(dict(body=field.body.name, group=group, x=x[corners],
                               pressure=values[corners, 0], status=values[corners, 1],
                               X=_pad3(field.X[corners.ravel()]).reshape(corners.shape + (3,))))
        for group in sorted(master_groups):
            if field.mesh.groups.get(group) is None:
                continue
            _, corners = _facets(field, group)
            masters.append(dict(body=field.body.name, group=group, x=x[corners]))
    rigids = []
    u = problem.u.getArray(readonly=True)
    for r in problem.scene.rigids:
        rows = problem.rigid_dofs(r.name).ravel()
        scale = warp if amplify == "total" else 1.0
        pair = next((problem.pair_of(c) for c in problem.scene.contacts if c.master == r.name),
                    None)
        rigids.append(dict(rigid=turned(r, None if pair is None
                                        else scale * pair.obstacle_rotation),
                           U=_pad3(u[rows][None] * scale)[0] if len(rows) else None))
    return dict(bodies=bodies, slaves=slaves, masters=masters, rigids=rigids)


def _merge(pieces: list[dict]) -> dict:
    """Rank 0: join the pieces of all ranks (bodies by name, facets by group)."""
    bodies: dict[str, list] = {}
    for p in pieces:
        for b in p["bodies"]:
            bodies.setdefault(b["name"], []).append(b)
    merged_bodies = []
    for name, parts in bodies.items():
        tops, types, xs, offset = [], [], [], 0
        for b in parts:
            # the flat VTK cell array n, i_1..i_n, n, ... (one cell type per body mesh)
            top = b["topology"].reshape(len(b["cell_types"]), -1).copy()
            top[:, 1:] += offset
            tops.append(top.ravel())
            types.append(b["cell_types"])
            xs.append(b["x"])
            offset += len(b["x"])
        merged_bodies.append(dict(name=name, topology=np.concatenate(tops),
                                  cell_types=np.concatenate(types), x=np.concatenate(xs),
                                  von_mises=np.concatenate([b["von_mises"] for b in parts])))

    def join(kind):
        groups: dict[tuple, list] = {}
        for p in pieces:
            for s in p[kind]:
                groups.setdefault((s["body"], s["group"]), []).append(s)
        out = []
        for (body, group), parts in groups.items():
            keys = [k for k in parts[0] if k not in ("body", "group")]
            out.append(dict(body=body, group=group,
                            **{k: np.concatenate([s[k] for s in parts]) for k in keys}))
        return out

    rigids = [r for r in pieces[0]["rigids"]]
    return dict(bodies=merged_bodies, slaves=join("slaves"), masters=join("masters"),
                rigids=rigids)


# -------------------------------------------------------------- pyvista objects
def _facet_polydata(x: np.ndarray) -> pyvista.PolyData:
    """PolyData of facets given by their corner coordinates (n, nc, 3): lines or polygons."""
    n, nc, _ = x.shape
    points = x.reshape(-1, 3)
    conn = np.hstack([np.full((n, 1), nc), np.arange(n * nc).reshape(n, nc)]).ravel()
    if nc == 2:
        return pyvista.PolyData(points, lines=conn)
    return pyvista.PolyData(points, faces=conn)


def turned(rigid, rotation: Optional[Sequence[float]]):
    """A scene ``Rigid`` with its geometry turned by ``rotation`` about its reference point (a
    picture scales it as the translations, as a small rotation's displacements); as it is
    without."""
    if rotation is None or not np.any(rotation):
        return rigid
    from dolfinx_friction.fem.obstacles import Obstacle, rotation_matrix
    obstacle = Obstacle.like(rigid)
    moved = obstacle.moved(rotation_matrix(rotation, len(obstacle.pivot)))
    return dataclasses.replace(rigid, **{key: tuple(float(c) for c in moved[key])
                                         for key in ("point", "normal", "center", "axis")
                                         if moved[key] is not None})


def _rigid_shape(rigid, U: np.ndarray, gdim: int, bounds: np.ndarray, focus: np.ndarray):
    """A pyvista object for a rigid obstacle, sized from the bodies' bounding box."""
    lo, hi = bounds
    size = float(np.linalg.norm(hi - lo)) or 1.0
    U = np.zeros(3) if U is None else U
    if rigid.shape == "plane":
        n = _pad3(np.asarray(rigid.normal, float)[None])[0]
        n /= np.linalg.norm(n)
        p0 = _pad3(np.asarray(rigid.point, float)[None])[0] + U
        c = focus - np.dot(focus - p0, n) * n  # foot of the bodies' centre on the plane
        if gdim == 2:
            t = np.array([n[1], -n[0], 0.0])
            half, depth = 0.6 * size, 0.04 * size
            quad = np.array([c - half * t, c + half * t, c + half * t - depth * n,
                             c - half * t - depth * n])
            return pyvista.PolyData(quad, faces=[4, 0, 1, 2, 3])
        return pyvista.Plane(center=c, direction=n, i_size=1.2 * size, j_size=1.2 * size)
    if rigid.shape == "sphere":
        c = _pad3(np.asarray(rigid.center, float)[None])[0] + U
        if gdim == 2:
            disk = pyvista.Circle(radius=rigid.radius, resolution=180)
            return disk.translate(c, inplace=False)
        return pyvista.Sphere(radius=rigid.radius, center=c, theta_resolution=60,
                              phi_resolution=60)
    if rigid.shape == "cylinder":
        a = np.asarray(rigid.axis, float) / np.linalg.norm(rigid.axis)
        p0 = np.asarray(rigid.point, float) + U
        c = p0 + np.dot(focus - p0, a) * a
        extent = float(np.abs((hi - lo) @ a)) or size
        return pyvista.Cylinder(center=c, direction=a, radius=rigid.radius,
                                height=1.2 * extent, resolution=90)
    raise ValueError(f"unknown rigid shape {rigid.shape!r}")


def _status_cmap():
    from matplotlib.colors import ListedColormap
    return ListedColormap(list(STATUS_COLORS))


def _scalar_args(scalar: str, clim: tuple[float, float], bar: bool, title: str) -> dict:
    common = dict(show_scalar_bar=bar, nan_color=STATUS_COLORS[0])
    bar_args = dict(title="", vertical=False, height=0.09, width=0.5, position_x=0.33,
                    position_y=0.05 if scalar == "status" else 0.02, title_font_size=16,
                    label_font_size=14, color="black")
    if scalar == "status":
        return dict(common, cmap=_status_cmap(), clim=[OPEN - 0.5, SLIP + 0.5], n_colors=3,
                    scalar_bar_args=dict(bar_args, n_labels=0),
                    annotations={float(OPEN): "open", float(STICK): "stick",
                                 float(SLIP): "slip"})
    return dict(common, cmap="plasma", clim=list(clim),
                scalar_bar_args=dict(bar_args, fmt="%.3g", n_labels=5))


def render(result_or_problem, png_path: Union[str, Path], scalar: str = "contact_pressure",
           warp: float = 1.0, amplify: str = "total",
           panels: Optional[Sequence[str]] = None,
           title: Optional[str] = None, window_size: Optional[tuple[int, int]] = None,
           show_edges: bool = True, contact_margin: float = 0.75,
           clim: Optional[tuple[float, float]] = None,
           view: Optional[Sequence[float]] = None,
           body_scalar: Optional[str] = None) -> Optional[Path]:
    """Render the current state of a solved problem into ``png_path`` (collective).

    ``result_or_problem``: a :class:`~dolfinx_friction.scene.runner.RunResult` or a
    :class:`~dolfinx_friction.scene.build.ContactProblem`.  ``scalar``:
    ``"contact_pressure"`` (nodal ``F_N/A_p`` of the closed slave nodes, grey
    elsewhere on the slave surface) or ``"status"`` (open / stick / slip).
    ``warp``: scale of the displacements (rigid obstacles are translated by
    ``warp`` times their displacement, so that the picture stays consistent).
    ``amplify="deformation"`` scales only the part of each body's displacement
    that differs from its mean translation (useful after a large slide), and
    draws the rigid obstacles at their true position.
    ``panels``: any of ``"overview"``, ``"contact"`` (default both; only the
    overview when nothing is in contact).  ``contact_margin``: the close-up
    shows the bounding box of the closed contact nodes enlarged by this
    fraction of its size on every side (at least a few element sizes).
    ``view``: 3D overview camera direction (from the scene towards the camera,
    z up); default isometric ``(1, 1, 1)``.  2D scenes are always seen along ``-z``.
    ``body_scalar="von_mises"`` colours the bodies by their von Mises stress (per cell)
    instead of one colour each.
    Returns the path on rank 0, ``None`` on the other ranks.
    """
    if amplify not in ("total", "deformation"):
        raise ValueError(f"amplify must be 'total' or 'deformation', not {amplify!r}")
    if scalar not in ("contact_pressure", "status"):
        raise ValueError(f"scalar must be 'contact_pressure' or 'status', not {scalar!r}")
    if body_scalar not in (None, "von_mises"):
        raise ValueError(f"body_scalar must be None or 'von_mises', not {body_scalar!r}")
    problem = _problem_of(result_or_problem)
    comm = problem.comm
    pieces = comm.gather(_local_pieces(problem, warp, amplify), root=0)
    if comm.rank != 0:
        return None
    return draw(_merge(pieces), problem.gdim, png_path, scalar=scalar, warp=warp,
                amplify=amplify, panels=panels, title=title, window_size=window_size,
                show_edges=show_edges, contact_margin=contact_margin, clim=clim, view=view,
                body_scalar=body_scalar)


def draw(data: dict, gdim: int, png_path: Union[str, Path], scalar: str = "contact_pressure",
         warp: float = 1.0, amplify: str = "total", panels: Optional[Sequence[str]] = None,
         title: Optional[str] = None, window_size: Optional[tuple[int, int]] = None,
         show_edges: bool = True, contact_margin: float = 0.75,
         clim: Optional[tuple[float, float]] = None, view: Optional[Sequence[float]] = None,
         body_scalar: Optional[str] = None) -> Path:
    """Draw the picture of :func:`render` from plain arrays into ``png_path`` (one process).

    ``data``: ``bodies`` (per body: ``name``, VTK ``topology`` and ``cell_types`` of
    corner-node cells, deformed point coordinates ``x`` (n, 3), ``von_mises`` per cell),
    ``slaves`` (per slave facet group: ``body``, ``group``, deformed corner coordinates
    ``x`` (n_facets, corners, 3), nodal ``pressure`` and ``status`` (n_facets, corners)
    in the codes of :mod:`~dolfinx_friction.fem.contact_fields`: -1 no element, 0 open,
    1 stick, 2 slip; 3D facets with outward normals), ``masters`` (per master facet
    group: ``body``, ``group``, ``x``; may be empty) and ``rigids`` (per obstacle: the
    :class:`~dolfinx_friction.scene.model.Rigid` and its drawn translation ``U`` (3,) or
    None).  ``warp`` and ``amplify`` only label the picture here (``x`` and ``U`` are
    already scaled); the other arguments as in :func:`render`.  This is what
    :func:`render` draws for a live problem and what ``dolfinx-friction render`` draws
    from the files of a run.
    """
    png_path = Path(png_path)
    png_path.parent.mkdir(parents=True, exist_ok=True)

    all_x = np.concatenate([b["x"] for b in data["bodies"]])
    bounds = np.stack([all_x.min(0), all_x.max(0)])
    centre = all_x.mean(0)
    closed_pts = [s["x"].reshape(-1, 3)[s["status"].ravel() >= STICK] for s in data["slaves"]]
    closed_pts = np.concatenate(closed_pts) if closed_pts else np.zeros((0, 3))
    if panels is None:
        panels = ("overview", "contact") if len(closed_pts) else ("overview",)
    pressures = np.concatenate([s["pressure"].ravel() for s in data["slaves"]] or [np.zeros(1)])
    if clim is None:
        pmax = float(pressures.max()) if pressures.size else 0.0
        clim = (0.0, pmax if pmax > 0 else 1.0)
    values_key = "status" if scalar == "status" else "pressure"
    bar_title = "status" if scalar == "status" else "contact pressure"

    if window_size is None:
        window_size = (900 * len(panels), 760)
    pl = pyvista.Plotter(shape=(1, len(panels)), off_screen=True, window_size=window_size,
                         border=False)
    pl.set_background("white")

    # facet size: a length scale for markers and margins
    lengths = [np.linalg.norm(s["x"][:, 1] - s["x"][:, 0], axis=1) for s in data["slaves"]]
    h = float(np.median(np.concatenate(lengths))) if lengths and len(lengths[0]) else \
        0.02 * float(np.linalg.norm(bounds[1] - bounds[0]))

    for col, panel in enumerate(panels):
        pl.subplot(0, col)
        close_up = panel == "contact"
        if close_up and len(closed_pts):
            lo, hi = closed_pts.min(0), closed_pts.max(0)
            pad = np.maximum(contact_margin * (hi - lo).max(), 4 * h)
            view_lo, view_hi = lo - pad, hi + pad
            if gdim == 3:
                view_lo[2], view_hi[2] = lo[2] - pad, hi[2] + pad
            view_lo, view_hi = np.maximum(view_lo, bounds[0]), np.minimum(view_hi, bounds[1])
        else:
            view_lo, view_hi = bounds
        # bodies (in the 3D close-up only the slave bodies, seen from the master side)
        slave_bodies = {s["body"] for s in data["slaves"]}
        for k, b in enumerate(data["bodies"]):
            if close_up and gdim == 3:
                continue
            grid = pyvista.UnstructuredGrid(b["topology"], b["cell_types"], b["x"])
            colour = dict(color=BODY_COLORS[k % len(BODY_COLORS)])
            if body_scalar == "von_mises":
                grid.cell_data["von Mises stress"] = b["von_mises"]
                vm_max = max(float(np.percentile(c["von_mises"], 99)) for c in data["bodies"]
                             if c["name"] in slave_bodies) if slave_bodies else None
                colour = dict(scalars="von Mises stress", cmap="viridis",
                              clim=(0.0, vm_max) if vm_max else None,
                              show_scalar_bar=k == 0 and col == 0,
                              scalar_bar_args=dict(title="von Mises stress", fmt="%.3g",
                                                   position_x=0.05, position_y=0.05,
                                                   width=0.35, height=0.06))
            pl.add_mesh(grid, show_edges=show_edges, edge_color="#7f7f7f", line_width=0.5,
                        smooth_shading=False,
                        opacity=1.0 if (gdim == 2 or b["name"] in slave_bodies) else 0.55,
                        **colour)
        # rigid obstacles
        for r in data["rigids"]:
            shape = _rigid_shape(r["rigid"], r["U"], gdim, bounds, centre)
            if close_up and gdim == 3:
                continue
            pl.add_mesh(shape, color=RIGID_COLOR, opacity=1.0 if gdim == 2 else 0.35,
                        smooth_shading=gdim == 3)
        # master surfaces: outline in the 3D close-up
        if close_up and gdim == 3:
            for m in data["masters"]:
                pl.add_mesh(_facet_polydata(m["x"]), style="wireframe", color="#9a9a9a",
                            line_width=0.5, opacity=0.5)
        # slave surfaces coloured by the scalar
        lift = np.zeros(3)
        if gdim == 2:
            lift[2] = 1e-3 * float(np.linalg.norm(bounds[1] - bounds[0]))  # above the cells
        first_bar = col == len(panels) - 1
        for s in data["slaves"]:
            poly = _facet_polydata(s["x"] + lift)
            values = s[values_key].ravel().astype(float)
            if scalar == "contact_pressure":  # nodes not in contact: grey
                values = np.where(s["status"].ravel() >= STICK, values, np.nan)
                poly.point_data[bar_title] = values
            else:  # categories are not interpolated: a facet takes its weakest corner's state
                poly.cell_data[bar_title] = s["status"].min(axis=1).astype(float)
            args = _scalar_args(scalar, clim, first_bar, bar_title)
            first_bar = False
            if gdim == 2:
                pl.add_mesh(poly, scalars=bar_title, line_width=8 if close_up else 6,
                            interpolate_before_map=True, **args)
            else:
                pl.add_mesh(poly, scalars=bar_title, show_edges=close_up, edge_color="#404040",
                            line_width=0.5, interpolate_before_map=True,
                            **args)
            if close_up or gdim == 2:
                pts = pyvista.PolyData(s["x"].reshape(-1, 3) + 2 * lift)
                pts.point_data[bar_title] = values  # every node of a slave facet
                pl.add_mesh(pts, scalars=bar_title, render_points_as_spheres=True,
                            point_size=14 if close_up else 10,
                            **dict(_scalar_args(scalar, clim, False, bar_title)))
        # camera
        aspect = window_size[0] / len(panels) / window_size[1]
        if gdim == 2:
            _fit_parallel(pl, view_lo, view_hi, np.array([0.0, 0.0, 1.0]),
                          np.array([0.0, 1.0, 0.0]), aspect)
        elif close_up:
            n = mean_normal(data["slaves"])
            up = np.array([0.0, 1.0, 0.0]) if abs(n[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
            _fit_parallel(pl, view_lo, view_hi, n, up, aspect)
        else:
            box = [view_lo[0], view_hi[0], view_lo[1], view_hi[1], view_lo[2], view_hi[2]]
            if view is None:
                pl.view_isometric()
            else:
                direction = np.asarray(view, float) / np.linalg.norm(view)
                c = 0.5 * (view_lo + view_hi)
                dist = 3.0 * float(np.linalg.norm(view_hi - view_lo))
                pl.camera_position = [tuple(c + dist * direction), tuple(c), (0.0, 0.0, 1.0)]
            pl.reset_camera(bounds=box)
            pl.camera.zoom(0.9)
        label = title if (title and col == 0) else None
        text = {"overview": f"deformed, displacements x{warp:g}" if amplify == "total"
                else f"deformed, deformation x{warp:g} (about the mean translation)",
                "contact": "contact zone"}[panel]
        if close_up and gdim == 3:
            text += " (slave surface seen from the master side)"
        pl.add_text((label + "\n" if label else "") + text, position="upper_left",
                    font_size=10, color="black")
        if gdim == 3:
            pl.add_axes(color="black")
        if col == len(panels) - 1:  # the scalar bar's title, left of the bar
            width = window_size[0] / len(panels)
            pl.add_text(bar_title, position=(0.03 * width, 0.045 * window_size[1]),
                        font_size=11, color="black")
    for bar in pl.scalar_bars.values():  # readable over the mesh
        bar.SetDrawBackground(True)
        bar.GetBackgroundProperty().SetColor(1.0, 1.0, 1.0)
        bar.GetBackgroundProperty().SetOpacity(0.85)
    pl.screenshot(str(png_path))
    pl.close()
    return png_path


def _fit_parallel(pl, lo: np.ndarray, hi: np.ndarray, towards_camera: np.ndarray,
                  up: np.ndarray, aspect: float) -> None:
    """Parallel projection looking along ``-towards_camera`` that frames the box [lo, hi]."""
    n = towards_camera / np.linalg.norm(towards_camera)
    up = up - np.dot(up, n) * n
    up /= np.linalg.norm(up)
    right = np.cross(up, n)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])])
    c = 0.5 * (lo + hi)
    w = np.ptp(corners @ right)
    h = np.ptp(corners @ up)
    dist = 10.0 * float(np.linalg.norm(hi - lo)) + 1e-30
    pl.camera_position = [tuple(c + dist * n), tuple(c), tuple(up)]
    pl.enable_parallel_projection()
    pl.reset_camera_clipping_range()
    pl.camera.parallel_scale = 0.5 * max(1.3 * h, 1.1 * w / aspect, 1e-30)


def mean_normal(slaves: list[dict]) -> np.ndarray:
    """Mean outward normal of the closed slave facets (falls back to all facets)."""
    normals = []
    for s in slaves:
        x = s["x"]
        if x.shape[1] < 3:
            continue
        m = np.cross(x[:, 1] - x[:, 0], x[:, -1] - x[:, 0])
        closed = (s["status"] >= STICK).any(axis=1)
        normals.append(m[closed] if closed.any() else m)
    if not normals:
        return np.array([0.0, 0.0, -1.0])
    n = np.concatenate(normals).sum(0)
    return n / (np.linalg.norm(n) or 1.0)
