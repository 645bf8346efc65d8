"""The module paths of the flat layout (before 0.2), kept as aliases of their new homes
for one release: ``import dolfinx_friction.pair`` gives :mod:`dolfinx_friction.fem.node_to_surface`
with a :class:`DeprecationWarning`.  Three old modules became packages of the same name
(``scene``, ``viz``, ``cli``); their old names are the packages' own lazy names."""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import warnings

MOVED = {
    "compat": "_compat",
    "fields": "fem.numbering", "surfaces": "fem.surfaces", "interaction": "fem.pairing",
    "pair": "fem.node_to_surface", "assembly": "fem.pattern", "system": "fem.block_problem",
    "bulk": "fem.loads",
    "newton": "nls.newton", "stepping": "nls.stepping", "linear": "nls.linear",
    "model": "scene.model", "validation": "scene.validation", "problem": "scene.build",
    "solver": "scene.driver", "api": "scene.runner", "provenance": "scene.provenance",
    "gmsh_io": "io.gmsh", "mesh_cache": "io.mesh_cache", "inputs": "io.files",
    "output": "io.writer", "results": "io.reader", "time_series": "io.xdmf_series",
    "snapshot": "viz.snapshot", "plots": "viz.plots",
    "commands": "cli.commands", "progress": "cli.progress", "sweep": "cli.sweep",
    "analytic": "reference.analytic", "calculix": "reference.calculix",
    "postprocess": "reference.compare",
}


class _OldPaths(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds ``dolfinx_friction.<old>`` and loads it as its new module (the same object)."""

    def find_spec(self, fullname, path=None, target=None):
        package, _, old = fullname.rpartition(".")
        if package != __package__ or old not in MOVED:
            return None
        return importlib.machinery.ModuleSpec(fullname, self)

    def create_module(self, spec):
        return None

    def exec_module(self, module) -> None:
        old = module.__name__.rpartition(".")[2]
        new = f"{__package__}.{MOVED[old]}"
        warnings.warn(f"{module.__name__} is now {new}", DeprecationWarning, stacklevel=2)
        # the import system returns what sys.modules holds once the module is executed
        sys.modules[module.__name__] = importlib.import_module(new)


def install() -> None:
    """Puts the finder of the old paths on :data:`sys.meta_path` (once)."""
    if not any(isinstance(f, _OldPaths) for f in sys.meta_path):
        sys.meta_path.append(_OldPaths())
