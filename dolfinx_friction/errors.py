"""Which exceptions are the user's input at fault, and which a failed solve."""
from __future__ import annotations

import sys
from typing import Optional

EXIT_INTERNAL, EXIT_INPUT, EXIT_DIVERGED = 1, 2, 3


class OutputError(OSError):
    """The output directory cannot be prepared or written."""


# (module, class) of the errors that blame the input.  Looked up in sys.modules
# rather than imported: an exception of a module that was never imported cannot
# be raised, and a bad scene is then answered without importing dolfinx.
_INPUT_ERRORS = (("dolfinx_friction.scene", "SceneError"),
                 ("dolfinx_friction.gmsh_io", "MeshError"),
                 ("dolfinx_friction.problem", "ModelError"),
                 ("dolfinx_friction.errors", "OutputError"))
_DIVERGED_ERRORS = (("dolfinx_friction.solver", "ConvergenceError"),)


def _is(exc: BaseException, classes) -> bool:
    for module, name in classes:
        cls = getattr(sys.modules.get(module), name, None)
        if cls is not None and isinstance(exc, cls):
            return True
    return False


def classify(exc: BaseException) -> tuple[Optional[int], str]:
    """Exit status and one-line message for an expected error; (None, ...) for a bug."""
    message = " ".join(str(exc).split())
    if _is(exc, _INPUT_ERRORS):
        return EXIT_INPUT, message
    if _is(exc, _DIVERGED_ERRORS):
        return EXIT_DIVERGED, f"diverged: {message}"
    return None, message
