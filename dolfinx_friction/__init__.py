"""Node-to-surface penalty contact with Coulomb friction for DOLFINx.

The building blocks for a FEniCSx script (see the README, "Using the contact in your own
FEniCSx code"): :class:`NodeToSurface` (one contact pair on the user's spaces and facet
tags), :class:`Surface`, the rigid obstacles :func:`rigid_plane`, :func:`rigid_sphere`,
:func:`rigid_cylinder`, :func:`create_matrix`; :class:`BlockProblem` (bodies given by
UFL residuals, with contact), :class:`Newton`, :func:`solve_steps`, :func:`snes_solve`.
They import dolfinx on first use.

The package logs through :mod:`logging` (logger ``dolfinx_friction``, silent unless the
program configures logging) and prints nothing.  The form compiler's chatter (the C compiler
command lines that distutils logs at INFO on the root logger while dolfinx's JIT builds a
form or element) is dropped, unless the ``dolfinx_friction`` logger is enabled for DEBUG
(``dolfinx-friction --debug``); warnings and errors always pass.
"""
import logging
import re

__version__ = "0.1.0"


class _CompilerChatter(logging.Filter):
    """Drops distutils' records below WARNING unless the package logger is at DEBUG."""

    _DISTUTILS = re.compile(r"[\\/]_?distutils[\\/]")

    def filter(self, record: logging.LogRecord) -> bool:
        return (record.levelno >= logging.WARNING or not self._DISTUTILS.search(record.pathname)
                or logging.getLogger(__name__).isEnabledFor(logging.DEBUG))


logging.getLogger(__name__).addHandler(logging.NullHandler())
logging.getLogger().addFilter(_CompilerChatter())

_PUBLIC = {
    "NodeToSurface": "pair", "Surface": "pair", "ContactState": "pair",
    "ContactSetupError": "pair", "rigid_plane": "pair", "rigid_sphere": "pair",
    "rigid_cylinder": "pair", "create_matrix": "pair", "NO_ELEMENT": "pair",
    "BlockProblem": "system", "Newton": "newton", "NewtonTrace": "newton",
    "snes_solve": "newton", "solve_steps": "stepping", "IncrementRecord": "stepping",
    "ConvergenceError": "stepping",
    "Linear": "contact.laws", "Exponential": "contact.laws", "Tabular": "contact.laws",
}
__all__ = sorted(_PUBLIC)


def __getattr__(name: str):
    if name not in _PUBLIC:
        raise AttributeError(f"module 'dolfinx_friction' has no attribute {name!r}")
    import importlib
    return getattr(importlib.import_module(f"dolfinx_friction.{_PUBLIC[name]}"), name)


def __dir__():
    return sorted(list(globals()) + __all__)
