"""Which exceptions are the user's input at fault, and which a failed solve."""
from __future__ import annotations

from typing import Optional

EXIT_INPUT, EXIT_DIVERGED = 2, 3


def classify(exc: BaseException) -> tuple[Optional[int], str]:
    """Exit status and one-line message for an expected error; (None, ...) for a bug."""
    from dolfinx_friction.gmsh_io import MeshError
    from dolfinx_friction.output import OutputError
    from dolfinx_friction.problem import ModelError
    from dolfinx_friction.scene import SceneError
    from dolfinx_friction.solver import ConvergenceError
    message = " ".join(str(exc).split())
    if isinstance(exc, (SceneError, MeshError, ModelError, OutputError)):
        return EXIT_INPUT, message
    if isinstance(exc, ConvergenceError):
        return EXIT_DIVERGED, f"diverged: {message}"
    return None, message
