"""One body's fields of one increment in one XDMF file (dolfinx's ``XDMFFile``).

``XDMFFile`` writes functions of the mesh's geometry degree only: the displacement and the
nodal contact values, held on the body's space of degree k, are interpolated to degree g
where k != g (:func:`output_spaces`).  Version differences go through :mod:`_compat`.
"""
from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np

from dolfinx_friction import _compat as compat

__all__ = ["output_spaces", "write_fields"]


def output_spaces(field) -> dict:
    """The spaces of a body's output: ``vector_in``/``scalar_in`` of its degree,
    ``vector_out``/``scalar_out`` of its mesh's geometry degree (the same objects where the
    degrees agree)."""
    mesh = field.V.mesh
    g, k = compat.geometry_degree(mesh), compat.space_degree(field.V)
    scalar = compat.scalar_space(mesh, k)
    return {"vector_in": field.V, "scalar_in": scalar,
            "vector_out": field.V if k == g else compat.vector_space(mesh, g),
            "scalar_out": scalar if k == g else compat.scalar_space(mesh, g)}


def _output_function(values: np.ndarray, space_in, space_out, name: str, kept: dict):
    """A Function named ``name`` on ``space_out`` from owned ``values`` on ``space_in``;
    the Functions are ``kept[name]`` from one call to the next (refilled from zero)."""
    if name not in kept:
        f = compat.function(space_in)
        kept[name] = f, f if space_out is space_in else compat.function(space_out)
    f, g = kept[name]
    f.x.array[:] = 0.0
    f.x.array[:values.size] = values.ravel()
    compat.scatter_forward(f)
    if g is not f:
        g.x.array[:] = 0.0
        g.interpolate(f)
    g.name = name
    return g


def write_fields(path: Path, field, spaces: dict, nodal: dict[str, np.ndarray], t: float,
                 cell_functions=(), kept: Optional[dict] = None) -> None:
    """The displacement, the nodal contact values (owned nodes, (n, 1) or (n, gdim)) and
    the cell functions of a body at pseudo-time ``t`` into one XDMF file (collective);
    ``kept``: the output Functions by name, for the next call (made here when missing)."""
    kept = {} if kept is None else kept
    from dolfinx.io import XDMFFile
    mesh = field.V.mesh
    owned = field.n_owned
    with XDMFFile(mesh.comm, str(path), "w") as xdmf:
        xdmf.write_mesh(mesh)
        u = field.u.x.array[: owned * field.gdim]
        xdmf.write_function(_output_function(u, spaces["vector_in"], spaces["vector_out"],
                                             "displacement", kept), t)
        for name, values in nodal.items():
            kind = "vector" if values.shape[1] > 1 else "scalar"
            xdmf.write_function(_output_function(values[:owned], spaces[f"{kind}_in"],
                                                 spaces[f"{kind}_out"], name, kept), t)
        for f in cell_functions:
            xdmf.write_function(f, t)
    if mesh.comm.rank == 0:
        _xinclude_namespace(Path(path))


#: XInclude's namespace; dolfinx 0.11 writes it with ``https``, which libxml2 (VTK's XDMF
#: reader, ParaView) does not know: their reader then finds no mesh for the functions'
#: grids (VTK 9.6 crashes on them)
XINCLUDE = "http://www.w3.org/2001/XInclude"


def _xinclude_namespace(path: Path) -> None:
    """Write XInclude's namespace in ``path`` as the XML standard spells it."""
    text = path.read_text()
    fixed = text.replace(f'xmlns:xi="{XINCLUDE.replace("http:", "https:")}"',
                         f'xmlns:xi="{XINCLUDE}"')
    if fixed != text:
        path.write_text(fixed)
