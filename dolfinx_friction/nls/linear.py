"""Linear solves of the Newton iteration.

The default solver is MUMPS (LU; LDL^T where the Jacobian is symmetric) with the
factorisation kept (``reuse``): it preconditions GMRES for later Jacobians.  In small
strain only the contact part, supported on the contact surface, changes between
iterations, so a few Krylov iterations of back-solves replace a factorisation (1.46x
faster at 67k dofs, same Newton iterations: benchmarks/RESULTS.md); GMRES stops at the
relative residual the caller asks (Newton's: :func:`~dolfinx_friction.nls.newton.forcing`).
It is kept across increments, also when a search changed the matrix pattern (the old
factors precondition the new matrix: 6-12 GMRES iterations on the 35k-dof sliding block),
and refactorised when GMRES does not converge within ``max_krylov`` iterations; then the
next :data:`PAUSE` Jacobians are factorised afresh as well (a stiff contact change can
need many Krylov iterations).  Keeping pays only where a factorisation costs many
back-solves: MUMPS's own counts (elimination flops RINFOG(3) against factor
entries INFOG(20)) decide, at least :data:`PAYBACK` back-solves; small 2D problems
factorise in milliseconds and are factorised every time.  A fresh factorisation is a
plain direct solve.  Every decision depends on counts, never on timings: runs are
repeatable.
A direct solve is checked: a factorisation that failed (a zero pivot) or a solution that
leaves a linear residual above :data:`SINGULAR` of the right-hand side means a singular
Jacobian (a body that only the contact held, and the contact opened): the solve fails
with that reason (:attr:`LinearSolver.failure`), and Newton with it.
Where the Jacobian splits into a constant bulk stiffness ``K`` and a contact tangent ``C``
(:meth:`~dolfinx_friction.fem.block_problem.BlockProblem.split`: linear bodies), the solve
can keep ``K``'s factorisation for the whole run instead (:class:`Condensed`): with ``A``
the dofs where ``C`` is not zero, ``G = (K^-1)_AA`` (one back-solve per dof the first time
it is active), ``x = K^-1 (b - P_A w)``, ``(I + C_AA G) w = C_AA (K^-1 b)_A`` (Woodbury's
identity), as the preconditioner of Richardson iterations on ``J`` (applied as
``K v + C v``, never assembled) until the true residual is below 1e-10 ``|b|`` (one
iteration on the Hertz benchmark; reactions as with LU to 1e-12).  It is used while its
flops so far (columns of ``G``, back-solves, dense solves; MUMPS's counts, a column of
``G`` at :data:`COLUMN_SHARE` of a back-solve's) stay below those of the solves it
replaced plus :data:`INVESTMENT` of them, else the path above is taken.  What a solve by
that path costs is its flops per solve so far (factorisations, and back-solves with a kept
one: a block of 16k dofs whose kept factorisation needs 13 GMRES iterations per Jacobian
costs a third of a factorisation per solve, and 1,000 columns of ``G`` would not pay back
there), known once that path solved (with a
factorisation it keeps: once that preconditioned a solve); ``K`` is factorised only if
``G``'s columns, at that path's back-solve flops, could pay (on a 35k-dof 3D block they
cannot: 0.67 s of factorisation was spent for nothing).  With frictionless pairs the same
``K^-1`` entries give Newton's step with the contact statuses solved for
(:meth:`Condensed.contact_step`, :mod:`~dolfinx_friction.nls.normal_qp`): two back-solves.
Under MPI the same: ``K`` is factorised by distributed MUMPS, ``G``'s columns come from
back-solves with distributed right-hand sides, and ``G``, ``C_AA`` and the dense solves are
kept on every rank (redundantly, :class:`Condensed`); every decision uses global counts.
A factorisation given the constrained rows (Newton gives them: identity rows with zero
right-hand side) solves on the free rows only (:mod:`~dolfinx_friction.nls.free_rows`):
MUMPS would otherwise order the held dofs with their neighbours (the one-layer ironing
holds u_z on every node: a quarter of the flops, half the time).  Where a nonlinear body
meets linear ones (serial), the linear bodies' interior is condensed out as well, its
factorisation kept for the run (:mod:`~dolfinx_friction.nls.interior`).  A factorisation
of a nonlinear body's Jacobian kept as GMRES's preconditioner (``reuse``) does not pay
there: 10-18 GMRES iterations per Jacobian on the ironing, each a tenth of a fresh
factorisation.  What pays there is Newton's chord step (:meth:`LinearSolver.solve_again`):
one back-solve with the last fresh factorisation, the Jacobian neither assembled nor
filled, through the same free rows and condensed interior.
An iterative solver (:data:`~dolfinx_friction.nls.defaults.ITERATIVE`: GMRES with
algebraic multigrid, or any Krylov solver the options give without ``ksp_rtol``) stops at
the relative residual Newton asks for each step (inexact Newton);
:func:`~dolfinx_friction.nls.defaults.choose` picks direct or iterative by the size of the
system (a scene's ``[solver] linear = "auto"``).
``symmetric=True`` (without user ``options``: Jacobians with the constrained rows and
columns eliminated, of frictionless contact between linear bodies,
:attr:`BlockProblem.symmetric`) factorises LDL^T (MUMPS, symmetric indefinite, from the
upper triangle): half the flops and entries of LU (0.28 against 0.42 s on a 16k-dof 3D
block), on one rank: MUMPS's distributed LDL^T stopped on a zero pivot for about 1 in 6
partitions of the Hertz cylinder demo on 3 ranks (the matrix symmetric to 6e-17, its LU
fine; dolfinx 0.5's partitions differ from run to run), so several ranks factorise LU.
The condensed path's ``K`` is factorised so whenever it is symmetric (linear
bodies, friction or not).  Their counts are doubled to LU's for every decision above.
``package="petsc"`` (one rank, without user ``options``) factorises with PETSc's own LU
(Cholesky where symmetric, nested-dissection ordering) instead of MUMPS, every Jacobian
afresh unless ``reuse`` is given: below
:data:`~dolfinx_friction.nls.defaults.NATIVE_MAX_DOFS` MUMPS's fixed cost per call exceeds
the elimination (:func:`~dolfinx_friction.nls.defaults.factorisation` chooses).  It does
not pivot: a solve it fails (a zero pivot, or the residual check) is done again by MUMPS,
which then stays; only MUMPS's failure is the solve's.
``reuse=False`` factorises every Jacobian.  With user ``options`` (another solver) the
default is ``reuse=False``: their preconditioner is rebuilt for every Jacobian.  Only an
LU or LDL^T factorisation is kept (``reuse`` is ignored for other preconditioners); one by
a solver other than MUMPS is kept whatever it cost.  Options go through PETSc's options
database under a prefix of the solver's own (``prefix`` plus a serial number, while the
solver lives): its defaults, the given ``options`` over them, and over both every option the
database has under ``prefix`` (the command line's win).  So two live solvers never read each
other's options.
"""
from __future__ import annotations

import itertools
import weakref
from typing import Iterable, Optional

import numpy as np
from petsc4py import PETSc

from dolfinx_friction import _compat as compat
from dolfinx_friction.nls.free_rows import FreeRows
from dolfinx_friction.nls import normal_qp
from dolfinx_friction.nls.interior import Interior, factor_entries

#: MUMPS without scaling (``ICNTL(8) = 0``): its default scaling is computed afresh at
#: every numeric factorisation, a ninth of each on the finite-strain ironing of
#: benchmarks/bench_ccx_nlgeom.py (45.8 -> 40.8 ms), and moved no Newton iteration and no
#: reaction beyond 1.4e-11 of the kinds measured (RESULTS, "Finite strain: cost per
#: Newton iteration")
MUMPS = {"mat_mumps_icntl_8": 0}
DIRECT = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps",
          **MUMPS}
#: MUMPS's ordering of the condensed system ``J_PP - D`` of
#: :mod:`~dolfinx_friction.nls.interior` (its Schur complement ``D`` a dense block): AMF.
#: Estimated elimination flops (RINFOG(1)) AMF / PORD, MUMPS's automatic choice there (no
#: METIS or SCOTCH in the packages): 8.4e6 / 1.5e7 on the press + shear block of
#: benchmarks/bench_ccx_nlgeom.py, 1.13e7 / 1.15e7 and 3.24e8 / 3.66e8 on its test and full
#: ironing.  (Elsewhere the automatic choice stays: on the 3D Hertz and sliding-block
#: demos PORD is the cheaper one, on the 2D Hertz cylinder AMF, by 4-24 %.)
CONDENSED_ORDERING = {"mat_mumps_icntl_7": 2}
#: MUMPS's orderings by the number it reports (INFOG(7))
MUMPS_ORDERINGS = {0: "amd", 2: "amf", 3: "scotch", 4: "pord", 5: "metis", 6: "qamd"}
#: PETSc's own factorisation, for small serial systems
#: (:func:`~dolfinx_friction.nls.defaults.factorisation`)
NATIVE = {"ksp_type": "preonly", "pc_factor_mat_solver_type": "petsc",
          "pc_factor_mat_ordering_type": "nd"}
#: the packages a default solver may factorise with
PACKAGES = ("mumps", "petsc")
#: GMRES's relative residual with a kept factorisation, unless the caller asks otherwise
KRYLOV_RTOL = 1e-12
REUSE = {"ksp_type": "gmres", "ksp_gmres_restart": 20, "ksp_atol": 0.0,
         "pc_type": "lu", "pc_factor_mat_solver_type": "mumps", **MUMPS}  # max_it: max_krylov
#: Jacobians factorised afresh after GMRES failed with a kept factorisation.
PAUSE = 3
#: Keep a factorisation only if it costs at least this many back-solves (in flops).
PAYBACK = 100
#: A direct solve whose linear residual exceeds this share of the right-hand side's norm
#: found no solution: the Jacobian is singular (measured on well-posed scenes: <= 1e-11).
SINGULAR = 1e-6


class LinearSolver:
    """Solves ``J x = b`` for a sequence of Jacobians, with PETSc options under ``prefix``."""

    def __init__(self, comm, prefix: str = "dolfinx_friction_", reuse: Optional[bool] = None,
                 options: Optional[dict] = None, max_krylov: int = 20, symmetric: bool = False,
                 package: str = "mumps"):
        if package not in PACKAGES:
            raise ValueError(f"package = {package!r}: must be one of "
                             f"{', '.join(map(repr, PACKAGES))}")
        #: PETSc's own factorisation (``package="petsc"``, without ``options``: see the
        #: module's docstring), MUMPS's after a failure
        self._native = package == "petsc" and not options and comm.size == 1
        if reuse is None:
            reuse = options is None and not self._native
        self._prefix, self._options, self._symmetric = prefix, options or {}, symmetric
        self.ksp = self._configured(comm, reuse)
        pc = self.ksp.getPC()
        #: the Jacobians must be symmetric (:meth:`BlockProblem.jacobian` with ``symmetric``)
        self.symmetric = pc.getType() in ("cholesky", "icc")
        # only a factorisation is kept; only MUMPS reports what it cost
        self.reuse, self.max_krylov = reuse and pc.getType() in ("lu", "cholesky"), max_krylov
        self._counted = self.reuse and pc.getFactorSolverType() == "mumps"
        #: a Krylov solver (not a kept factorisation) stops at the relative residual each
        #: solve asks, unless the options fix ``ksp_rtol``
        self._inexact = (not self.reuse and self.ksp.getType() != "preonly"
                         and "ksp_rtol" not in options)
        self._factored_size: Optional[tuple] = None  # of the matrix last factorised
        self._paused = 0  # Jacobians still to factorise afresh
        self._pays = False  # the last factorisation is worth keeping
        self._solve_flops = 0.0  # of one back-solve with the last factorisation
        #: flops and solves of this path so far (factorisations, back-solves), the cost
        #: per solve the condensed path is measured against
        self._spent, self._solves = 0.0, 0
        self.factorisations = 0
        self.krylov_iterations = 0
        #: why the last solve failed ("" if it did not)
        self.failure = ""
        self._condensed: Optional[Condensed] = None
        self.condensed_solves = 0
        #: steps with the frictionless contacts' statuses solved for (:meth:`solve_contact`)
        self.contact_steps = 0
        #: a factorisation (any package) solves on the free rows where they are given
        self._factorises = pc.getType() in ("lu", "cholesky")
        self._free_rows = FreeRows()
        self._operator_sizes: Optional[tuple] = None  # of the matrix the KSP last had
        self._interior: Optional[Interior] = None
        #: (J, constrained, constant) of the last solve where it factorised J afresh and
        #: succeeded: what :meth:`solve_again` solves with
        self._last: Optional[tuple] = None
        self._fresh = False  # the last attempt factorised
        #: solves with the last factorisation by :meth:`solve_again`
        self.chord_solves = 0
        #: MUMPS's ordering in its last fresh factorisation (:data:`MUMPS_ORDERINGS`)
        self._ordering = ""
        #: the package that factorised the condensed-out interior, once that path was taken
        self._interior_package = ""

    def _configured(self, comm, reuse: bool) -> PETSc.KSP:
        """A KSP with this solver's defaults and options under a prefix of its own."""
        options = self._options
        ldlt = self._symmetric and not options and comm.size == 1  # see the module's docstring
        defaults = {**(REUSE if reuse else DIRECT), **({"pc_type": "cholesky"} if ldlt else {}),
                    **(NATIVE if self._native else {})}
        # they stay while this solver may factorise (MUMPS reads its own then)
        own, written = private_options(self._prefix, {**defaults, **options})
        self._written = written  # (more are written with the condensed path's ordering)
        weakref.finalize(self, forget_options, written).atexit = False
        return self._new_ksp(comm, own)

    @staticmethod
    def _new_ksp(comm, prefix: str) -> PETSc.KSP:
        """A KSP set from the options database under this solver's own ``prefix``."""
        ksp = PETSc.KSP().create(comm)
        ksp.setOptionsPrefix(prefix)
        ksp.setFromOptions()
        return ksp

    def settings(self) -> dict:
        """The solver in use: ``ksp_type`` (``gmres`` on a kept factorisation, when one is
        kept), ``pc_type``, ``factor_solver_type`` (factorisations only), ``ordering``
        (PETSc's; MUMPS's in its last fresh factorisation, once there was one),
        ``reuse_factorisation``; ``interior_factor_solver_type``, once the linear bodies'
        interior was condensed out (:class:`~dolfinx_friction.nls.interior.Interior`): the
        package that factorised it."""
        pc = self.ksp.getPC()
        out = {"ksp_type": "gmres" if self.reuse else self.ksp.getType(),
               "pc_type": pc.getType()}
        if pc.getType() in ("lu", "cholesky", "ilu", "icc"):
            out["factor_solver_type"] = pc.getFactorSolverType()
            if out["factor_solver_type"] == "petsc":
                out["ordering"] = PETSc.Options().getString(
                    self.ksp.getOptionsPrefix() + "pc_factor_mat_ordering_type", "nd")
            elif self._ordering:
                out["ordering"] = self._ordering
        out["reuse_factorisation"] = self.reuse
        if self._interior_package:
            out["interior_factor_solver_type"] = self._interior_package
        return out

    def release(self) -> None:
        """Free the factorisations and matrices this solver keeps (collective): its counts
        and :meth:`settings` stay, and its next solve factorises afresh.  (petsc4py leaves
        a PETSc object that Python collected to ``PETSc.garbage_cleanup``: a solver that is
        only dropped keeps its factorisations until then.)"""
        self.ksp.reset()
        self._operator_sizes = self._factored_size = self._last = None
        self._pays = False
        self._free_rows.destroy()
        for part in (self._condensed, self._interior):
            if part is not None:
                part.destroy()
        self._condensed = self._interior = None

    def solve_split(self, split, b: PETSc.Vec, x: PETSc.Vec) -> Optional[bool]:
        """Solve with the Jacobian given as bulk plus contact
        (:class:`~dolfinx_friction.fem.jacobian.JacobianSplit`) by :class:`Condensed`; None when
        that does not pay (or failed): then :meth:`solve` with the assembled Jacobian."""
        if not (self.reuse and self._counted) or self._solves < (2 if self._pays else 1):
            return None  # priced once this path solved (with a factorisation it keeps: twice)
        if self._condensed is None:
            self._condensed = Condensed(b.getComm(), self.ksp.getOptionsPrefix(),
                                        split.symmetric)
        if not self._condensed.solve(split, b, x, self._spent / self._solves,
                                     self._solve_flops):
            return None
        self.condensed_solves += 1
        self._last = None
        return True

    def solve_contact(self, split, models: list, b: PETSc.Vec, x: PETSc.Vec
                      ) -> Optional[bool]:
        """Newton's step with the frictionless contacts' statuses solved for, where the
        condensed path holds the bulk factorisation (:meth:`Condensed.contact_step`); None
        where it does not apply: then :meth:`solve_split` or :meth:`solve`."""
        if self._condensed is None:
            return None
        solved = self._condensed.contact_step(split, models, b, x)
        if solved:
            self._last = None
            self.contact_steps += 1
        return solved

    def solve(self, J: PETSc.Mat, b: PETSc.Vec, x: PETSc.Vec, rtol: float = KRYLOV_RTOL,
              constrained: Optional[np.ndarray] = None,
              constant: Optional[np.ndarray] = None) -> bool:
        """Solve; returns False when the solver failed (:attr:`failure` says why).
        ``rtol``: the relative residual a Krylov solve stops at (GMRES on a kept
        factorisation; a Krylov solver whose options do not fix ``ksp_rtol``).
        ``constrained``: owned local rows that are identity rows of ``J`` with zero
        right-hand side (:attr:`BlockProblem.constrained_rows`); a factorisation then solves
        on the other rows only (:class:`~dolfinx_friction.nls.free_rows.FreeRows`).
        ``constant`` (serial, with ``constrained``): free rows whose rows and columns are
        the same in every ``J`` of the run (:meth:`BlockProblem.linear_interior`), condensed
        out with their factorisation kept (:class:`~dolfinx_friction.nls.interior.Interior`)
        where that path is taken."""
        self._last = None
        if constrained is None or not self._factorises:
            ok = self._solve(J, b, x, rtol)
        else:
            if constant is not None and len(constant) and self._interior is None:
                self._interior = Interior(self.ksp.getOptionsPrefix())
            ok = self._restricted(lambda A, b_, x_: self._solve(A, b_, x_, rtol), J, b, x,
                                  constrained, constant, again=False)
        if ok and self._fresh and self._factorises:
            self._last = (J, constrained, constant)
        return ok

    def solve_again(self, b: PETSc.Vec, x: PETSc.Vec) -> bool:
        """Solve with the matrix and the factorisation of the last :meth:`solve` (a chord
        step of Newton's: nothing is assembled or factorised, one back-solve); False where
        the last solve left none (it failed, kept an older factorisation, or did not
        factorise) or the back-solve failed."""
        if self._last is None:
            return False
        J, constrained, constant = self._last
        if constrained is None:
            ok = self._back_solve(b, x)
        else:
            ok = self._restricted(lambda A, b_, x_: self._back_solve(b_, x_), J, b, x,
                                  constrained, constant, again=True)
        self.chord_solves += 1
        return ok

    def _restricted(self, solve, J, b, x, constrained, constant, again: bool) -> bool:
        """``solve(A, b_, x_)`` on the free rows, with the linear interior condensed out
        where that path is taken; ``again``: with the matrices of the last call."""
        interior = self._interior
        if constant is not None and len(constant) and (
                interior.usable if again else interior.set_up(J, constrained, constant)):
            self._written += write_options(self.ksp.getOptionsPrefix(), CONDENSED_ORDERING)
            self._interior_package = interior.package
            return interior.solve(solve, J, b, x, again)
        return self._free_rows.solve(solve, J, b, x, constrained, again)

    def _back_solve(self, b: PETSc.Vec, x: PETSc.Vec) -> bool:
        """``x`` from the factorisation the solver holds (its operator unchanged); the
        Krylov method is left as it was (a user's, around a factorisation)."""
        kind = self.ksp.getType()
        self.ksp.setType("preonly")
        self.ksp.getPC().setReusePreconditioner(True)
        self.ksp.solve(b, x)
        ok = self.ksp.getConvergedReason() > 0
        self.ksp.setType(kind)
        return ok

    def _solve(self, J: PETSc.Mat, b: PETSc.Vec, x: PETSc.Vec, rtol: float) -> bool:
        """One solve of the system as given (with a kept factorisation where it pays)."""
        keep = (self.reuse and self._pays and not self._paused
                and J.getSize() == self._factored_size)
        self._paused = max(self._paused - 1, 0)
        ok = self._attempt(J, b, x, keep, rtol)
        if not ok and keep:
            self._paused = PAUSE
            ok = self._attempt(J, b, x, False, rtol)
        if not ok and self._native:  # it does not pivot: MUMPS answers before a failure
            self._native = False
            self.ksp.destroy()
            self.ksp = self._configured(b.getComm(), False)
            self._operator_sizes, self._factored_size = None, None
            ok = self._attempt(J, b, x, False, rtol)
        return ok

    def _attempt(self, J, b, x, keep: bool, rtol: float) -> bool:
        """One solve, with the kept factorisation or a fresh one; whether it converged."""
        self.failure = ""
        if self.reuse:
            self.ksp.setType("gmres" if keep else "preonly")
            self.ksp.setTolerances(rtol=rtol, max_it=self.max_krylov)
        elif self._inexact:
            self.ksp.setTolerances(rtol=rtol)
        if self._operator_sizes not in (None, J.getSizes()):
            self.ksp.reset()  # the free rows changed in number: PETSc keeps no old sizes
        self._operator_sizes = J.getSizes()
        self.ksp.setOperators(J, J)
        self.ksp.getPC().setReusePreconditioner(keep)
        self.ksp.solve(b, x)
        self._fresh = not keep
        if not keep:
            self.factorisations += 1
            self._factored_size = J.getSize()
            if self.ksp.getPC().getFactorSolverType() == "mumps":
                self._ordering = MUMPS_ORDERINGS.get(
                    self.ksp.getPC().getFactorMatrix().getMumpsInfog(7), "other")
            self._pays = self.reuse
            if self._counted:
                F = self.ksp.getPC().getFactorMatrix()
                flops, self._solve_flops = _costs(F, self.symmetric)
                self._pays = flops >= PAYBACK * self._solve_flops
                self._spent += flops
        self.krylov_iterations += self.ksp.getIterationNumber()
        self._spent += max(self.ksp.getIterationNumber(), 1) * self._solve_flops
        self._solves += 1
        reason = self.ksp.getConvergedReason()
        if reason == compat.ksp_pc_failed():
            self.failure = "singular Jacobian (the factorisation met a zero pivot)"
            # never solve with (or keep) a failed factorisation: MUMPS then fails in its
            # solve phase (INFOG(1) = -3) on the next Jacobian, seen under MPI
            self._factored_size, self._pays = None, False
            prefix = self.ksp.getOptionsPrefix()
            self.ksp.destroy()
            self.ksp = self._new_ksp(b.getComm(), prefix)
            self._operator_sizes = None
        elif reason > 0 and self.ksp.getType() == "preonly":
            r = b.duplicate()
            J.mult(x, r)
            r.axpy(-1.0, b)
            residual, scale = r.norm(), b.norm()
            r.destroy()
            if not residual <= SINGULAR * scale:
                self.failure = (f"singular Jacobian (the linear residual is {residual:.2e} of "
                                f"{scale:.2e}: a body that nothing holds?)")
        elif reason <= 0:
            self.failure = f"the linear solver failed ({reason})"
        return reason > 0 and not self.failure


def release_garbage(comms: Iterable) -> None:
    """Destroy the PETSc objects Python has collected on each of ``comms`` (mpi4py or
    PETSc communicators; collective on each, in the same order on every rank): petsc4py
    leaves them to ``PETSc.garbage_cleanup``, so a long process that never calls it keeps
    every dropped matrix and factorisation."""
    for comm in comms:
        PETSc.garbage_cleanup(comm)


def write_options(prefix: str, options: dict) -> list[str]:
    """Write ``options`` into PETSc's options database under ``prefix`` where it does not
    have them yet (the command line wins); returns the names written."""
    opts, written = PETSc.Options(), []
    for key, value in options.items():
        if not opts.hasName(prefix + key):
            opts[prefix + key] = value
            written.append(prefix + key)
    return written


_SERIAL = itertools.count()


def private_options(prefix: str, options: dict) -> tuple[str, list[str]]:
    """Write ``options`` into PETSc's options database under a new prefix of their own
    (``prefix`` plus a serial number), each replaced by the database's value under
    ``prefix`` where it has one, together with every other option it has there (the command
    line wins); returns the new prefix and the names written."""
    own = f"{prefix}{next(_SERIAL)}_"
    database = PETSc.Options().getAll()
    given = {**options, **{name[len(prefix):]: value for name, value in database.items()
                           if name.startswith(prefix) and not name[len(prefix):][:1].isdigit()}}
    return own, write_options(own, given)


def forget_options(names: list[str]) -> None:
    """Remove options that :func:`write_options` wrote: a later solver in the process
    must not inherit them."""
    opts = PETSc.Options()
    for name in names:
        opts.delValue(name)


def _costs(F: PETSc.Mat, symmetric: bool) -> tuple[float, float]:
    """The flops of a MUMPS factorisation and of a back-solve with it (4 per entry), counted
    as for LU: an LDL^T's doubled (its one triangle is both), so that every decision is the
    one LU's counts would take."""
    scale = 2.0 if symmetric else 1.0
    return scale * F.getMumpsRinfog(3), scale * 4.0 * factor_entries(F)


#: The condensed path may spend at most this many solves' flops more than the solves it
#: replaced (the columns of ``G`` are paid before they pay back).
INVESTMENT = 4
#: Columns of ``K^-1`` computed per back-solve call (dense right-hand sides).
COLUMNS_PER_SOLVE = 64
#: A column of ``G`` is priced at this share of a back-solve's flops: computed among
#: :data:`COLUMNS_PER_SOLVE` right-hand sides at once (BLAS 3), it runs faster per flop
#: than the factorisation every cost here is weighed against; at that factorisation's
#: rate it costs 0.12-0.81 of a back-solve (benchmarks/bench_columns.py: MUMPS, elastic
#: stiffness of 220 to 14k rows, the smaller the cheaper).
COLUMN_SHARE = 0.5


class Condensed:
    """Solves ``(K + C) x = b`` with ``K``'s factorisation kept and ``C`` of low rank.

    ``G``, the entries of ``K^-1`` among the contact surfaces' dofs, is filled column by
    column as dofs become active and kept while ``K`` (the same matrix object) does; the
    whole columns ``K^-1 P`` too (this rank's rows) while they take no more entries than
    ``K``'s factors (then ``K^-1 (r - P_A w) = K^-1 r - (K^-1 P_A) w`` needs one back-solve
    instead of two).  Under MPI ``K`` is factorised by distributed MUMPS and ``G``'s columns
    come from back-solves with distributed right-hand sides; ``G``, ``C_AA`` (gathered from
    every rank's elements) and the dense solves with ``I + C_AA G`` are the same on every
    rank, done redundantly: each rank needs all of ``w`` for its rows of ``P_A w``, and a
    solve on one rank would add a broadcast to every preconditioner application while the
    others wait.  Every decision is taken on the same global counts on every rank.
    """

    def __init__(self, comm, prefix: str, symmetric: bool = False):
        self.comm = comm.tompi4py()
        self.bulk = PETSc.KSP().create(comm)
        self.bulk.setOptionsPrefix(prefix + "bulk_")
        self.bulk.setType("preonly")
        pc = self.bulk.getPC()
        self.symmetric = symmetric and self.comm.size == 1  # LDL^T on one rank (module doc)
        pc.setType("cholesky" if self.symmetric else "lu")
        pc.setFactorSolverType("mumps")
        self.bulk.setFromOptions()
        self.outer = PETSc.KSP().create(comm)
        self.outer.setOptionsPrefix(prefix + "condensed_")
        self.outer.setType("richardson")
        self.outer.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
        self.outer.setTolerances(rtol=1e-10, atol=0.0, max_it=10)
        pc = self.outer.getPC()
        pc.setType("python")
        pc.setPythonContext(_Callbacks(self))
        self.outer.setFromOptions()
        self._K: Optional[PETSc.Mat] = None
        self._regular = False  # K's factorisation succeeded
        self._J: Optional[PETSc.Mat] = None
        self._Z: Optional[list] = None
        self._solve_flops = 0.0
        self._y: Optional[PETSc.Vec] = None
        self._dofs = np.zeros(0, np.int64)
        self._G = np.zeros((0, 0))
        self._known = np.zeros(0, bool)  # per surface dof: its column of G is computed
        self._column = np.zeros(0, np.int64)  # per surface dof: its column in _G
        self._active = np.zeros(0, np.int64)  # the dofs where C is not zero (global)
        self._at_active = _Gather()  # a vector's values at the active dofs, on every rank
        self.columns = 0  # back-solves spent on G
        self._at_model = _Gather()  # ... at the dofs of contact_step's elements
        self._solved_for: Optional[np.ndarray] = None  # the r whose K^-1 r _y holds
        self.solves = 0  # solves done, each instead of a factorisation
        self._spent = 0.0  # flops spent on them (estimated)
        self.iterations = 0  # Richardson iterations

    def destroy(self) -> None:
        """Destroy its factorisation and PETSc objects (collective); ``K`` is the caller's."""
        for obj in (self.bulk, self.outer, self._J, self._y, self._at_active, self._at_model):
            if obj is not None:
                obj.destroy()

    def _factorise(self, K: PETSc.Mat) -> bool:
        """Factorise ``K``; whether MUMPS succeeded."""
        self._K = K
        self.bulk.setOperators(K, K)
        self.bulk.setUp()
        F = self.bulk.getPC().getFactorMatrix()
        if F.getMumpsInfog(1) < 0:
            return False
        _, self._solve_flops = _costs(F, self.symmetric)
        self._entries = factor_entries(F)  # whole columns of K^-1 are kept while they fit
        self._J = None  # the operator K + C
        self._dofs = np.zeros(0, np.int64)
        self._y, self._solved_for = K.createVecLeft(), None
        return True

    def _set_dofs(self, dofs: np.ndarray) -> None:
        """The surface dofs ``G`` is kept on (all its columns are forgotten when they
        change, or when ``K`` is factorised again)."""
        if not np.array_equal(dofs, self._dofs):
            self._dofs, self._G = dofs, np.zeros((len(dofs), 0))
            self._known = np.zeros(len(dofs), bool)
            self._column = np.zeros(len(dofs), np.int64)
            self._Z = []

    def _add_columns(self, where: np.ndarray) -> None:
        """Columns of ``K^-1`` of the surface dofs at ``where``, restricted to the surface
        dofs, appended to ``G`` (collective: distributed back-solves, rows gathered)."""
        F = self.bulk.getPC().getFactorMatrix()
        n = self._K.getSize()[0]
        start, end = self._K.getOwnershipRange()
        owned = (self._dofs >= start) & (self._dofs < end)
        rows = self._dofs[owned] - start  # this rank's surface dofs, local
        new = []
        for first in range(0, len(where), COLUMNS_PER_SOLVE):
            chunk = where[first:first + COLUMNS_PER_SOLVE]
            rhs = np.zeros((end - start, len(chunk)), order="F")
            mine = owned[chunk]
            rhs[self._dofs[chunk][mine] - start, np.flatnonzero(mine)] = 1.0
            sizes = ((end - start, n), (None, len(chunk)))
            B = PETSc.Mat().createDense(sizes, array=rhs, comm=self._K.getComm())
            X = PETSc.Mat().createDense(sizes, comm=self._K.getComm())
            X.setUp()
            F.matSolve(B, X)
            part = X.getDenseArray()
            # the ranks' rows in rank order: the sorted surface dofs
            new.append(np.vstack(self.comm.allgather(part[rows])))
            if self._Z is not None:
                self._Z.append(part.copy())
            B.destroy()
            X.destroy()
        self._column[where] = self._G.shape[1] + np.arange(len(where))
        self._known[where] = True
        self._G = np.hstack([self._G] + new)
        self.columns += len(where)
        if self._Z is not None and n * self._G.shape[1] > self._entries:
            self._Z = None  # no more memory for whole columns than the factors take

    def _active_entries(self, split) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The contact entries of every rank (collective): the sorted global ``active`` dofs
        and all ranks' ``rows``, ``cols``, ``values`` in rank order."""
        entries = [(split.rows, split.cols, split.values)]
        if self.comm.size > 1:
            entries = self.comm.allgather(entries[0])
        rows, cols, values = (np.concatenate(e) for e in zip(*entries))
        return np.unique(np.concatenate([rows, cols])), rows, cols, values

    def solve(self, split, b: PETSc.Vec, x: PETSc.Vec, replaced: float,
              solve_flops: float) -> bool:
        """Solve with the kept bulk factorisation; False (``x`` undefined) when this path
        does not pay here or did not converge: the caller solves another way (collective:
        the same answer on every rank).  ``replaced``: the flops of a solve by the other
        path, ``solve_flops``: of a back-solve there (``K``'s estimate before it is
        factorised); both MUMPS's global counts."""
        active, rows, cols, values = self._active_entries(split)

        def cost(columns: int, per_column: float) -> float:
            """Flops of this solve on all ranks: new columns of G, back-solves, the dense
            solves (on every rank)."""
            return ((COLUMN_SHARE * columns + 8) * per_column
                    + self.comm.size * 2.0 / 3.0 * len(active) ** 3)

        budget = replaced * (self.solves + 1 + INVESTMENT) - self._spent
        if split.bulk is not self._K:
            # all of G's columns at the other path's back-solve flops: if they do not pay,
            # K's factorisation is not paid either
            if cost(len(active), solve_flops) > budget:
                return False
            self._regular = self._factorise(split.bulk)
        if not self._regular:  # e.g. a body held by the contact alone: K is singular
            return False
        self._set_dofs(split.dofs)
        where = np.searchsorted(self._dofs, active).clip(max=max(len(self._dofs) - 1, 0))
        if len(active) and (not len(self._dofs) or (self._dofs[where] != active).any()):
            return False  # a coupling off the surfaces: not the split assumed
        new = where[~self._known[where]]
        flops = cost(len(new), self._solve_flops)
        if flops > budget:
            return False
        self._spent += flops
        if len(new):
            self._add_columns(new)
        n = len(active)
        C = np.bincount(np.searchsorted(active, rows) * n + np.searchsorted(active, cols),
                        weights=values, minlength=n * n).reshape(n, n)
        self._set_active(active)
        self._C, self._cols = C, self._column[where]
        if self._Z is not None and len(self._Z) > 1:
            self._Z = [np.hstack(self._Z)]
        self._M = np.eye(n) + C @ self._G[np.ix_(where, self._cols)]
        if self._J is None:
            self._J = PETSc.Mat().createPython(self._K.getSizes(), _Callbacks(self),
                                               comm=self._K.getComm())
            self._J.setUp()
        self.outer.setOperators(self._J, self._J)
        try:
            self.outer.solve(b, x)
        except (PETSc.Error, np.linalg.LinAlgError):  # I + C G singular: J is, or nearly
            return False
        self.iterations += self.outer.getIterationNumber()
        ok = self.outer.getConvergedReason() > 0
        self.solves += ok
        return ok

    def contact_step(self, split, models: list, b: PETSc.Vec, x: PETSc.Vec) -> Optional[bool]:
        """Newton's step with the frictionless contacts' statuses solved for
        (:mod:`~dolfinx_friction.nls.normal_qp`), from ``K``'s kept factorisation: True
        (``x`` the step) where the program changes a status decisively
        (:meth:`~dolfinx_friction.nls.normal_qp.Elements.changes`), None otherwise (Newton's
        own step, with the law's exact tangent, follows), where the program is not
        numerically positive definite, or where ``K`` is not the one this path factorised
        (collective: the same on every rank)."""
        if split.bulk is not self._K or not self._regular:
            return None
        el = normal_qp.gather(self.comm, models, split.fixed)
        self._set_dofs(split.dofs)
        where = np.searchsorted(self._dofs, el.dofs).clip(max=max(len(self._dofs) - 1, 0))
        if len(el.dofs) and (not len(self._dofs) or (self._dofs[where] != el.dofs).any()):
            return None  # a dof off the contact surfaces: not the split assumed
        new = where[~self._known[where]]
        self._spent += (COLUMN_SHARE * len(new) + 2) * self._solve_flops
        if len(new):
            self._add_columns(new)
        cols = self._column[where]
        G = self._G[np.ix_(where, cols)]
        y = self._y
        self._solved_for = None
        self.bulk.solve(b, y)  # K^-1 b
        AG = el.A @ G
        W = (el.A @ AG.T).T
        kept = el.force + el.s  # the forces the law's model carries now
        y_D = self._at_model(y, el.dofs)
        q = el.d - el.A @ y_D + AG @ (el.A.T @ kept)  # d - A K^-1 r_b
        lam = normal_qp.normal_forces(W, el.k, q)
        if lam is None or not el.changes(lam, q - W @ lam):
            self._solved_for = b.getArray(readonly=True).copy()  # y = K^-1 b, for apply
            return None
        load = el.A.T @ (kept - lam)  # on el.dofs: x = K^-1 (b - P_D load)
        if self._Z:
            if len(self._Z) > 1:
                self._Z = [np.hstack(self._Z)]
            x.setArray(y.getArray(readonly=True) - self._Z[0][:, cols] @ load)
        else:
            start, end = self._K.getOwnershipRange()
            owned = (el.dofs >= start) & (el.dofs < end)
            rhs = b.copy()
            values = rhs.getArray()
            values[el.dofs[owned] - start] -= load[owned]
            rhs.setArray(values)
            self.bulk.solve(rhs, x)
            rhs.destroy()
        return True

    def _set_active(self, active: np.ndarray) -> None:
        """The active dofs (global, sorted) and this rank's among them."""
        self._active = active
        start, end = self._K.getOwnershipRange()
        owned = (active >= start) & (active < end)
        self._owned, self._local = owned, active[owned] - start

    def mult(self, mat, v: PETSc.Vec, y: PETSc.Vec) -> None:
        """``y = (K + C) v``: the Jacobian, without assembling it."""
        self._K.mult(v, y)
        values = y.getArray().copy()
        values[self._local] += (self._C @ self._at_active(v, self._active))[self._owned]
        y.setArray(values)

    def apply(self, pc, r: PETSc.Vec, z: PETSc.Vec) -> None:
        """``z = (K + C)^-1 r`` (up to round-off): the preconditioner."""
        y = self._y
        same = self._solved_for is not None and np.array_equal(self._solved_for,
                                                               r.getArray(readonly=True))
        kept = self.comm.allreduce(int(not same)) == 0
        self._solved_for = None
        if not kept:  # (else y holds K^-1 r from contact_step)
            self.bulk.solve(r, y)
        w = np.linalg.solve(self._M, self._C @ self._at_active(y, self._active))
        if self._Z:  # K^-1 (r - P_A w) = y - (K^-1 P_A) w, from the kept columns
            w_all = np.zeros(self._Z[0].shape[1])
            w_all[self._cols] = w
            z.setArray(y.getArray(readonly=True) - self._Z[0] @ w_all)
            return
        values = r.getArray(readonly=True).copy()
        values[self._local] -= w[self._owned]
        y.setArray(values)
        self.bulk.solve(y, z)


class _Gather:
    """The values of a distributed vector at given global dofs, on every rank (collective;
    the scatter kept while the dofs are the same)."""

    def __init__(self) -> None:
        self._kept: Optional[tuple] = None  # (dofs, scatter, sequential vector)

    def __call__(self, v: PETSc.Vec, dofs: np.ndarray) -> np.ndarray:
        """(len(dofs),) ``v`` at ``dofs`` (a view, valid until the next call)."""
        if self._kept is None or not np.array_equal(self._kept[0], dofs):
            self.destroy()
            target = PETSc.Vec().createSeq(len(dofs), comm=PETSc.COMM_SELF)
            index = PETSc.IS().createGeneral(dofs.astype(PETSc.IntType), comm=PETSc.COMM_SELF)
            self._kept = (dofs.copy(), PETSc.Scatter().create(v, index, target, None), target)
            index.destroy()
        _, scatter, target = self._kept
        scatter.scatter(v, target, addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        return target.getArray(readonly=True)

    def destroy(self) -> None:
        """Destroy the scatter and vector it keeps."""
        if self._kept is not None:
            self._kept[1].destroy()
            self._kept[2].destroy()
            self._kept = None


class _Callbacks:
    """The Python context of :class:`Condensed`'s operator and preconditioner, calling it
    through a weak reference: PETSc keeps a context where Python's collector does not see
    it, so a :class:`Condensed` that was its own context would never be collected (nor its
    factorisation freed)."""

    def __init__(self, owner: Condensed):
        self._owner = weakref.ref(owner)

    def mult(self, mat, v: PETSc.Vec, y: PETSc.Vec) -> None:
        self._owner().mult(mat, v, y)

    def apply(self, pc, r: PETSc.Vec, z: PETSc.Vec) -> None:
        self._owner().apply(pc, r, z)
