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


class ConvergenceError(RuntimeError):
    """An increment that failed after all its cutbacks (one-line message): ``increment``
    (1, 2, ... within its step) starting at pseudo-time ``t``, the last residual norm, why
    (``reason``: a singular Jacobian, a non-finite state, an imbalance, ...; "" if Newton
    merely did not converge), the converged increments before it (``records``) and the
    cutbacks and Newton iterations spent on it.  The one class of that name: the stepping
    raises it, a scene run raises it again with the step named."""

    def __init__(self, message: str, increment: int = 0, t: float = 0.0,
                 residual: float = float("nan"), reason: str = "", records: tuple = (),
                 cutbacks: int = 0, iterations: int = 0):
        super().__init__(message)
        self.increment, self.t, self.residual, self.reason = increment, t, residual, reason
        self.records, self.cutbacks, self.iterations = list(records), cutbacks, iterations
