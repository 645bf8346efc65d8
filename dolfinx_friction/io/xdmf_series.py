"""A body's fields as one time series: an XDMF temporal collection over the per-increment
field files, which ParaView opens (and animates) as one dataset.

The per-increment files ``fields/<folder>/<body>.xdmf`` are what dolfinx's ``XDMFFile``
wrote: a mesh grid, and per function a temporal collection of one grid that includes the
mesh by XPointer.  Each increment becomes one uniform grid of the collection
``fields/<body>.xdmf``: that file's topology and geometry, every attribute it holds, and
the increment's pseudo-time; its HDF5 datasets are referred to by relative path
(``<folder>/<body>.h5:/...``), so the results folder can be moved.  Nothing about the
writer's names is assumed beyond the XDMF schema: grids, topology, geometry, attributes
and HDF ``DataItem`` elements.  No dolfinx here.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

HEADER = '<?xml version="1.0"?>\n<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>\n<Xdmf Version="3.0">\n'
INDENT = "  "
LEVEL = 3  # an increment's grid in Xdmf / Domain / Grid (the collection)


def increment_grid(xdmf: Path, t: float) -> str:
    """One increment's uniform grid (XML text, indented) for the collection in ``xdmf``'s
    grandparent.

    Parameters
    ----------
    xdmf : a per-increment file ``<fields>/<folder>/<body>.xdmf`` as dolfinx wrote it.
    t : the increment's pseudo-time (``t`` of history.csv).
    """
    root = ET.parse(xdmf).getroot()
    mesh = next((g for g in root.iter("Grid") if g.find("Topology") is not None
                 and g.find("Geometry") is not None), None)
    if mesh is None:
        raise ValueError(f"{xdmf}: no grid with a topology and a geometry")
    grid = ET.Element("Grid", Name=xdmf.parent.name, GridType="Uniform")
    grid.append(mesh.find("Topology"))
    grid.append(mesh.find("Geometry"))
    ET.SubElement(grid, "Time", Value=f"{t:.17g}")
    grid.extend(root.iter("Attribute"))
    for item in grid.iter("DataItem"):
        if item.get("Format") == "HDF" and item.text:
            file, sep, dataset = item.text.strip().partition(":")
            if not Path(file).is_absolute():
                file = f"{xdmf.parent.name}/{file}"
            item.text = f"{file}{sep}{dataset}"
    ET.indent(grid, INDENT, level=LEVEL)
    return INDENT * LEVEL + ET.tostring(grid, encoding="unicode").strip() + "\n"


def collection(name: str, grids: list[str]) -> str:
    """The XDMF document of a temporal collection ``name`` of ``grids`` (from
    :func:`increment_grid`), in time order."""
    # (ElementTree quotes the name; xml.sax.saxutils would import urllib: ~40 ms)
    grid = ET.tostring(ET.Element("Grid", Name=name, GridType="Collection",
                                  CollectionType="Temporal"), encoding="unicode")
    return (f"{HEADER}{INDENT}<Domain>\n{INDENT * 2}{grid.removesuffix(' />')}>\n"
            f'{"".join(grids)}'
            f"{INDENT * 2}</Grid>\n{INDENT}</Domain>\n</Xdmf>\n")
