"""Exception classes shared by the layers of the library (the command line maps them, and
the others, to its exit statuses: :mod:`dolfinx_friction.cli.exits`)."""
from __future__ import annotations


class OutputError(OSError):
    """The output directory cannot be prepared or written."""


class Interrupted(BaseException):
    """A run stopped at a checkpoint because its caller asked it to
    (:class:`~dolfinx_friction.scene.control.RunControl`): ``code`` is what the caller
    answered (the command line: the number of the signal it got).  A BaseException, like
    KeyboardInterrupt, so that no ``except Exception`` on the way out takes it for a failure
    of the solve."""

    def __init__(self, code: int):
        super().__init__(code)
        self.code = code


class ContactSetupError(ValueError):
    """A contact pair or a system that cannot be built from what it was given: a bad
    keyword, a rigid obstacle's geometry, a body nothing holds (one-line message)."""
