"""The contact added to a dolfinx ``fem.petsc.NonlinearProblem`` (dolfinx 0.10+), solved by
its own SNES.

A user who writes their bodies the dolfinx 0.10/0.11 way::

    problem = NonlinearProblem(F, u, bcs=bcs, petsc_options_prefix="block_",
                               petsc_options={"snes_linesearch_type": "none", ...})
    contact = add_contact(problem, [pair], bcs=bcs, history=[plasticity])
    for t in times:
        ...set the loads at t...
        reason = contact.solve()       # begin, problem.solve(), commit (or roll back)

gets the contact's forces and exact tangent in the SNES callbacks (after dolfinx's own
assembly, which stays as it is), a matrix whose sparsity also holds the contact
couplings (made again after every search), the contact search per increment, and the
friction history committed with the converged increment or rolled back with a failed
one, together with the user's own history (``history``: objects with ``commit()`` and
``rollback()``, e.g. the quadrature-point state of a plasticity model).

``F`` may be one form (one body and rigid obstacles) or a list of forms (several bodies,
``kind="mpi"``: the contact's numbering is dolfinx's block numbering, see
:class:`~dolfinx_friction.fem.node_to_surface.NodeToSurface`'s ``spaces``).
"""
from __future__ import annotations

import weakref
from collections.abc import Sequence
from typing import Protocol

from petsc4py import PETSc

from dolfinx_friction import _compat as compat
from dolfinx_friction.errors import ContactSetupError
from dolfinx_friction.fem.contact_settings import MAX_AUGMENTATIONS
from dolfinx_friction.fem.node_to_surface import NodeToSurface, create_matrix

__all__ = ["History", "SNESContact", "add_contact"]

#: the options prefix of this package's own solvers (Newton, snes_solve, LinearSolver)
PACKAGE_PREFIX = "dolfinx_friction_"


class History(Protocol):
    """A piece of history (state at the last converged increment) a cutback must undo."""

    def commit(self) -> None: ...

    def rollback(self) -> None: ...


class SNESContact:
    """Contact pairs joined to a dolfinx 0.10+ ``NonlinearProblem`` (made by
    :func:`add_contact`)."""

    def __init__(self, problem, contacts: Sequence[NodeToSurface], bcs: Sequence = (),
                 history: Sequence[History] = ()):
        parts = compat.snes_problem(problem)
        self.problem, self.contacts = problem, list(contacts)
        self.bcs, self.history = list(bcs), list(history)
        self.snes: PETSc.SNES = parts.snes
        prefix = self.snes.getOptionsPrefix() or ""
        if prefix.startswith(PACKAGE_PREFIX):
            raise ContactSetupError(f"add_contact: the problem's options prefix {prefix!r} is "
                                    f"this package's own ({PACKAGE_PREFIX!r}...): choose another")
        self._forms = parts.J
        spaces = parts.spaces
        for c in self.contacts:
            if len(c.spaces) != len(spaces) or any(a is not b for a, b in zip(c.spaces, spaces)):
                raise ContactSetupError(
                    f"{c.name}: its spaces are not the problem's ({len(spaces)} unknown(s)): "
                    f"give NodeToSurface(..., spaces=[u.function_space for u in the problem's u])")
        for h in self.history:
            if not (callable(getattr(h, "commit", None))
                    and callable(getattr(h, "rollback", None))):
                raise ContactSetupError(f"history: {h!r} has no commit() and rollback()")
        b, (residual, r_args, r_kwargs) = self.snes.getFunction()
        _A, _P, (jacobian, j_args, j_kwargs) = self.snes.getJacobian()
        if hasattr(residual, "contact"):
            raise ContactSetupError("add_contact: this problem already has contacts added")
        self._user = ((residual, r_args, r_kwargs or {}), (jacobian, j_args, j_kwargs or {}))
        self._b = b
        self._callbacks = _callbacks(self)
        self.snes.setFunction(self._callbacks[0], b)
        self.A: PETSc.Mat | None = None
        self._started = False

    # ------------------------------------------------------------- increments
    def begin(self) -> None:
        """Start an increment at the problem's current solution (collective): search, and
        a matrix whose sparsity holds the bodies' forms and the new contact couplings."""
        x = self.problem.x
        compat.assign_to_vector(self.problem.u, x)
        for c in self.contacts:
            c.begin(x)
            c.update(x, search=False)  # paired at the first iterate
        self._new_matrix()
        self._started = True

    def solve(self) -> int:
        """One increment: :meth:`begin`, the problem's ``solve()`` (its SNES) and, for
        contacts with ``method="augmented"``, again after each update of their multipliers
        (:meth:`NodeToSurface.augment`, at most
        :data:`~dolfinx_friction.fem.contact_settings.MAX_AUGMENTATIONS`), then
        :meth:`commit` if SNES converged on current pairings, else :meth:`rollback` with
        the solution Functions back at the increment's start: also where it converged on a
        contact's stale pairing (:meth:`NodeToSurface.stale_pairing`: cut the increment
        back) and where SNES raises (e.g. with ``snes_error_if_not_converged``: then the
        error propagates).  Returns SNES's converged reason (> 0 converged;
        ``DIVERGED_MAX_IT`` where the updates did not end or a pairing was stale)."""
        self.begin()
        start = self.problem.x.copy()
        try:
            self.problem.solve()
            reason, updates = self.snes.getConvergedReason(), 0
            while reason > 0 and any([c.augment() for c in self.contacts]):
                if updates == MAX_AUGMENTATIONS:
                    reason = PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT
                    break
                updates += 1
                self.problem.solve()
                reason = self.snes.getConvergedReason()
            if reason > 0 and any([c.stale_pairing() for c in self.contacts]):
                reason = PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT
            if reason > 0:
                self.commit()
            else:
                self._restore(start)
            return reason
        except BaseException:
            self._restore(start)
            raise
        finally:
            start.destroy()

    def _restore(self, start: PETSc.Vec) -> None:
        """The solution (vector and Functions) back at ``start``; the histories rolled back."""
        start.copy(self.problem.x)
        compat.assign_from_vector(self.problem.x, self.problem.u)
        self.rollback()

    def commit(self) -> None:
        """Accept the increment: the contacts' and ``history``'s state become the start of
        the next one."""
        for c in self.contacts:
            c.commit()
        for h in self.history:
            h.commit()
        self._started = False

    def rollback(self) -> None:
        """Undo the increment's history changes (contacts and ``history``) before a retry."""
        for c in self.contacts:
            c.rollback()
        for h in self.history:
            h.rollback()
        self._started = False

    # ------------------------------------------------------------- SNES callbacks
    # SNES evaluates the residual at line-search trials as well as at its iterates, and
    # the Jacobian only at its iterates: so the contacts are paired (slave nodes to master
    # faces) where the Jacobian is evaluated, at the start of each Newton step, and
    # frozen in every residual evaluation; where pairing changed the contacts, the
    # residual SNES holds for that iterate is evaluated again before its step is solved.
    def _residual(self, snes: PETSc.SNES, x: PETSc.Vec, b: PETSc.Vec) -> None:
        (residual, args, kwargs), _ = self._user
        residual(snes, x, b, *args, **kwargs)  # dolfinx's: bodies, lifting, Dirichlet rows
        self._require_started()
        for c in self.contacts:
            c.update(x, pairing=False, search=False)
        for c in self.contacts:
            c.add_residual(b, self.bcs)

    def _jacobian(self, snes: PETSc.SNES, x: PETSc.Vec, A: PETSc.Mat, P: PETSc.Mat) -> None:
        before = [c.evaluations for c in self.contacts]
        for c in self.contacts:
            c.update(x, search=False)
        if [c.evaluations for c in self.contacts] != before:
            self._residual(snes, x, snes.getFunction()[0])
        _, (jacobian, args, kwargs) = self._user
        jacobian(snes, x, A, P, *args, **kwargs)  # dolfinx's: bodies, Dirichlet rows
        for c in self.contacts:
            c.add_jacobian(A, self.bcs)

    def _new_matrix(self) -> None:
        if self.A is not None:
            self.A.destroy()
        self.A = create_matrix(self._forms, self.contacts)
        self.snes.setJacobian(self._callbacks[1], self.A, self.A)

    def _require_started(self) -> None:
        if not self._started:
            raise ContactSetupError("the contacts have not begun this increment: call "
                                    "SNESContact.solve() (or begin() before problem.solve())")


def _callbacks(contact: SNESContact) -> tuple:
    """The SNES callbacks of ``contact``, holding it by a weak reference: no reference cycle
    through the problem's SNES, so the objects are freed where the user drops them, on every
    rank at once (PETSc's destroy is collective; a garbage collector's pass comes at a
    different moment on each rank)."""
    ref = weakref.ref(contact)

    def residual(snes, x, b):
        ref()._residual(snes, x, b)

    def jacobian(snes, x, A, P):
        ref()._jacobian(snes, x, A, P)

    residual.contact = jacobian.contact = ref
    return residual, jacobian


def add_contact(problem, contacts: Sequence[NodeToSurface], bcs: Sequence = (),
                history: Sequence[History] = ()) -> SNESContact:
    """Add ``contacts`` to a dolfinx ``fem.petsc.NonlinearProblem`` (dolfinx 0.10+): their
    forces and tangent join the problem's SNES callbacks; ``bcs``: the problem's Dirichlet
    conditions (the contact leaves their rows and columns as dolfinx makes them);
    ``history``: the user's own state to commit and roll back with the contacts'.
    Raises :class:`~dolfinx_friction.ContactSetupError` (one line) for a problem of an
    older dolfinx, a nest matrix, contacts on other spaces, or a problem with contacts."""
    return SNESContact(problem, contacts, bcs, history)
