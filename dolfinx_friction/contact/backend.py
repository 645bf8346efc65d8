"""Which implementation evaluates the contact element: compiled kernels or numpy.

The public functions ``project`` (projection.py), ``face_kinematics``,
``rigid_kinematics`` and ``evaluate`` (element.py) dispatch here, so every
caller follows one switch:

* ``"auto"`` (default): the numba kernels of :mod:`~dolfinx_friction.contact.kernels`
  when numba imports, the numpy reference otherwise;
* ``"numba"``: the kernels, an error if numba does not import;
* ``"numpy"``: the numpy reference (``*_numpy`` functions).

The environment variable ``DOLFINX_FRICTION_KERNELS`` sets the start value;
:func:`use` changes it at run time, for good or (as a context manager) for a
block::

    with backend.use("numpy"):
        ...
"""
from __future__ import annotations

import os
from types import ModuleType
from typing import Optional

ENV = "DOLFINX_FRICTION_KERNELS"
CHOICES = ("auto", "numba", "numpy")

_choice: Optional[str] = None  # None until first use: then read from ENV
_kernels: Optional[ModuleType] = None
_import_error: Optional[BaseException] = None


class use:
    """Select ``"auto"``, ``"numba"`` or ``"numpy"``; as a context manager, restore the
    previous choice on exit."""

    def __init__(self, choice: str):
        if choice not in CHOICES:
            raise ValueError(f"kernels must be one of {CHOICES}, not {choice!r}")
        global _choice
        self.previous = _choice
        _choice = choice
        if choice == "numba":
            _load(required=True)

    def __enter__(self) -> "use":
        return self

    def __exit__(self, *exc) -> None:
        global _choice
        _choice = self.previous


def _load(required: bool) -> Optional[ModuleType]:
    """The kernels module, imported once (numba's import costs ~0.3 s)."""
    global _kernels, _import_error
    if _kernels is None and _import_error is None:
        # numba's coloured messages init colorama, which writes a colour reset to a
        # terminal at exit: under mpirun (ranks write to a pty) that is a stray line
        os.environ.setdefault("NUMBA_DISABLE_ERROR_MESSAGE_HIGHLIGHTING", "1")
        try:
            from dolfinx_friction.contact import kernels
            _kernels = kernels
        except Exception as err:  # ImportError, or a numba that rejects this numpy
            _import_error = err
    if _kernels is None and required:
        raise ImportError(f"compiled contact kernels unavailable: {_import_error!r}")
    return _kernels


def compiled() -> Optional[ModuleType]:
    """The kernels module if the current choice uses it, else None (use numpy)."""
    global _choice
    if _choice is None:
        _choice = os.environ.get(ENV, "auto").strip().lower() or "auto"
        if _choice not in CHOICES:
            raise ValueError(f"{ENV} must be one of {CHOICES}, not {_choice!r}")
    if _choice == "numpy":
        return None
    return _load(required=_choice == "numba")


def active() -> str:
    """``"numba"`` or ``"numpy"``: what the next call will run."""
    return "numpy" if compiled() is None else "numba"


def warm() -> None:
    """Initialise numba's typing and target contexts now, as a first kernel call would
    (~0.15 s CPU): for a process that runs kernels later (a sweep's worker, while it waits
    for its first point).  Nothing when the numpy reference is in use."""
    if compiled() is None:
        return
    from numba.core.registry import cpu_target
    cpu_target.typing_context.refresh()
    cpu_target.target_context.refresh()
