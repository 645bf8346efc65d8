"""The layers' import rules (docs/architecture.md), checked by walking every import
statement of the package, module level and inside functions alike."""
from __future__ import annotations

import ast
from functools import cache
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "dolfinx_friction"
HEAVY = {"dolfinx", "ufl", "basix", "ffcx", "petsc4py", "mpi4py", "gmsh", "pyvista"}


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


@cache
def imports(module: str) -> frozenset[str]:
    """Every module ``module`` names in an import statement (absolute names)."""
    found = set()
    for node in ast.walk(ast.parse(MODULES[module].read_text())):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0, f"{module}: relative import"
            found.add(node.module)
            found.update(f"{node.module}.{a.name}" for a in node.names
                         if f"{node.module}.{a.name}" in MODULES)
    return frozenset(found)


def closure(module: str) -> set[str]:
    """The modules ``module`` imports, directly or through the package's own modules."""
    seen, todo = set(), [module]
    while todo:
        for name in imports(todo.pop()):
            if name not in seen:
                seen.add(name)
                if name in MODULES:
                    todo.append(name)
    return seen


def layer(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _in(names, layers) -> list[str]:
    return sorted(n for n in names if n.startswith("dolfinx_friction.")
                  and layer(n) in layers and not n.endswith("._lazy"))


def _heavy(names) -> list[str]:
    return sorted(n for n in names if n.split(".")[0] in HEAVY)


@pytest.mark.parametrize("module", sorted(m for m in MODULES if layer(m) == "contact"))
def test_contact_core_imports_no_dolfinx(module):
    assert not _heavy(closure(module))
    assert not _in(closure(module), {"fem", "nls", "scene", "io", "viz", "cli", "reference"})


@pytest.mark.parametrize("module", sorted(m for m in MODULES if layer(m) in {"fem", "nls"}))
def test_building_block_and_solvers_read_no_scene(module):
    assert not _in(closure(module), {"scene", "io", "viz", "cli", "reference"})


@pytest.mark.parametrize("module", ["dolfinx_friction.scene.model",
                                    "dolfinx_friction.scene.validation",
                                    "dolfinx_friction.scene.toml",
                                    "dolfinx_friction.io.reader",
                                    "dolfinx_friction.io.files",
                                    "dolfinx_friction.viz.plots"])
def test_models_readers_and_plots_import_no_dolfinx(module):
    assert not _heavy(closure(module))


@pytest.mark.parametrize("module", sorted(m for m in MODULES if layer(m) != "cli"
                                          and m != "dolfinx_friction.__main__"))
def test_nothing_imports_the_cli(module):
    assert not _in(imports(module), {"cli"})


def test_the_rules_see_the_imports():
    """The walker finds what a module imports (a rule that can never fail proves nothing)."""
    assert "dolfinx_friction.contact.element" in closure("dolfinx_friction.fem.node_to_surface")
    assert _heavy(closure("dolfinx_friction.fem.block_problem"))
    assert _in(closure("dolfinx_friction.cli.frontend"), {"scene"})
