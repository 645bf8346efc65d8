"""Node-to-surface penalty contact with Coulomb friction for DOLFINx.

The building blocks for a FEniCSx script (see the README, "Using the contact in your own
FEniCSx code"): :class:`NodeToSurface` (one contact pair on the user's spaces and facet
tags), :class:`Surface`, the rigid obstacles :func:`rigid_plane`, :func:`rigid_sphere`,
:func:`rigid_cylinder`, :func:`rigid_sdf` (a signed distance), :func:`create_matrix`;
:class:`BlockProblem` (bodies given by UFL residuals, with contact), :class:`Newton`,
:func:`solve_steps`, :func:`snes_solve`; :func:`revolution_weight` and
:func:`axisymmetric_grad` for axisymmetric bodies.
They import dolfinx on first use.

The package logs through :mod:`logging` (logger ``dolfinx_friction``, silent unless the
program configures logging) and prints nothing.  The form compiler's chatter (the C compiler
command lines that distutils logs at INFO on the root logger while dolfinx's JIT builds a
form or element) is dropped, unless the ``dolfinx_friction`` logger is enabled for DEBUG
(``dolfinx-friction --debug``); warnings and errors always pass.
"""
import logging
import re

from dolfinx_friction import _moved
from dolfinx_friction._lazy import lazy_names

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
    "NodeToSurface": "fem.node_to_surface", "Surface": "fem.node_to_surface",
    "ContactState": "fem.node_to_surface", "ContactSetupError": "fem.node_to_surface",
    "rigid_plane": "fem.node_to_surface", "rigid_sphere": "fem.node_to_surface",
    "rigid_cylinder": "fem.node_to_surface", "rigid_sdf": "fem.node_to_surface",
    "create_matrix": "fem.node_to_surface",
    "NO_ELEMENT": "fem.node_to_surface", "BlockProblem": "fem.block_problem",
    "Newton": "nls.newton", "NewtonTrace": "nls.newton", "snes_solve": "nls.newton",
    "SNESNewton": "nls.newton",
    "solve_steps": "nls.stepping", "IncrementRecord": "nls.stepping",
    "ConvergenceError": "errors", "add_contact": "fem.snes", "SNESContact": "fem.snes",
    "Linear": "contact.laws", "Exponential": "contact.laws", "Tabular": "contact.laws",
    "axisymmetric_grad": "fem.axisymmetric", "revolution_weight": "fem.axisymmetric",
}
__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
_moved.install()
