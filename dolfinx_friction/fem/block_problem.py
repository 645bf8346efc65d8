"""Bodies given by UFL residuals, coupled by contact, as one block system.

:class:`BlockProblem` joins one residual form ``F_i(u_i; v_i)`` per body into one
system.  The unknown is one PETSc vector :attr:`~BlockProblem.x`: the bodies' owned dofs
joined rank by rank, as dolfinx joins blocks (on each rank, the owned dofs of body 0, then
body 1, ...), then the translations of the rigid obstacles that are unknowns (rank 0).
The residual is ``R(x) = sum_i F_i(u_i) - f_ext + contact forces`` with zeros in the
constrained rows; the Jacobian is dolfinx's compiled assembly of every body's Jacobian,
plus the contact tangents, with identity rows where constrained.  A body whose Jacobian
does not depend on its displacement (a linear form) has it assembled once.

``x`` is the one copy of the displacement: the bodies' Functions are refreshed from it
(:meth:`~BlockProblem.scatter`) where an evaluation needs them and after every solve.
"""
from __future__ import annotations

import contextlib
import time
from dataclasses import dataclass, field
from typing import Optional, Sequence

import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx_friction import _compat as compat
from dolfinx_friction.fem.pattern import CooPattern
from dolfinx_friction.fem.rigid_motions import RigidMotions
from dolfinx_friction.fem.numbering import DofLayout
from dolfinx_friction.fem.node_to_surface import ContactSetupError, NodeToSurface, Surface

#: Residual norms below this many round-off units of the terms they sum (|J| |x| + |f_ext|
#: + the contact forces' sensitivity to the coordinates) are converged: Newton cannot
#: reduce them further.
ROUNDOFF_FLOOR = 2 * np.finfo(float).eps
#: A body's stiffness is symmetric when no entry differs from its transpose's by more than
#: this share of the largest row sum (compiled forms sum in another order: round-off)
SYMMETRY_TOL = 1e-12


@dataclass
class Timers:
    """Time per phase, seconds: ``phases`` wall clock, ``cpu`` this process's CPU time
    (on a shared machine the wall clock also counts the other jobs)."""

    phases: dict = field(default_factory=lambda: dict.fromkeys(PHASES, 0.0))
    cpu: dict = field(default_factory=lambda: dict.fromkeys(PHASES, 0.0))

    def add(self, phase: str, seconds: float, cpu: float = 0.0) -> None:
        self.phases[phase] += seconds
        self.cpu[phase] += cpu

    @contextlib.contextmanager
    def measure(self, phase: str):
        """Add the wall and CPU time of the ``with`` block to ``phase``."""
        wall, cpu = time.perf_counter(), time.process_time()
        try:
            yield
        finally:
            self.add(phase, time.perf_counter() - wall, time.process_time() - cpu)


@dataclass
class JacobianSplit:
    """The Jacobian ``J = K + C`` (serial): ``bulk`` is ``K``, the bodies' constant
    stiffness with the constrained rows made identity rows (a PETSc matrix, the same object
    while it does not change); ``C``, the contact tangent (zero in constrained rows), is the
    sum of the ``values`` at ``(rows, cols)`` (repeated pairs add), all within the contact
    surfaces' ``dofs`` (sorted).  With ``symmetric`` (``K`` is), the constrained columns
    are zero in both: ``J`` is ``jacobian(x, symmetric=True)``."""

    bulk: PETSc.Mat
    dofs: np.ndarray
    rows: np.ndarray
    cols: np.ndarray
    values: np.ndarray
    symmetric: bool = False


PHASES = ("setup", "contact_search", "contact_assembly", "bulk_assembly", "linear_solve",
          "output")


def _is_linear(jacobian: ufl.Form, u) -> bool:
    """Whether a Jacobian form does not depend on ``u`` (its body is linear)."""
    from ufl.algorithms import expand_derivatives
    return not expand_derivatives(ufl.derivative(jacobian, u)).integrals()


class _Body:
    """One block: compiled residual and Jacobian forms, its own vector and matrix."""

    def __init__(self, F: ufl.Form, u, J: Optional[ufl.Form], bcs: Sequence):
        V = u.function_space
        J = J if J is not None else ufl.derivative(F, u)
        self.u, self.V, self.bcs = u, V, list(bcs)
        self.linear = _is_linear(J, u)
        #: linear and zero at u = 0: its residual is the product of its Jacobian with u
        self.homogeneous = self.linear and not ufl.replace(
            F, {u: ufl.zero(*u.ufl_shape)}).integrals()
        self.F, self.J = compat.form(F), compat.form(J)
        self.b = compat.create_vector(self.F)
        self.A = compat.create_matrix(self.J)
        self.n_owned = V.dofmap.index_map.size_local * V.dofmap.index_map_bs

    def residual(self) -> np.ndarray:
        """Owned values of ``F(u)`` (ghost contributions summed)."""
        with self.b.localForm() as local:
            local.set(0.0)
        compat.assemble_vector_into(self.b, self.F)
        return self.b.getArray(readonly=True)[: self.n_owned]

    def jacobian_values(self) -> np.ndarray:
        """CSR values of the body's Jacobian at its current ``u`` (no bcs)."""
        self.A.zeroEntries()
        compat.assemble_matrix_into(self.A, self.J)
        return self.A.getValuesCSR()[2]


def _same(kept: tuple, key: tuple) -> bool:
    """Whether a cache's key holds the very objects of ``key`` (identity, not equality)."""
    return all(a is b for a, b in zip(kept, key))


class BlockProblem:
    """Residual and Jacobian of several bodies with contact, in one block numbering.

    Parameters
    ----------
    residuals : sequence of ufl.Form
        One UFL residual form per body, ``F_i(u_i; v_i)`` (internal minus external virtual
        work), linear in the test function.
    u : sequence of dolfinx Functions
        The bodies' displacements (vector Lagrange spaces of the mesh dimension); their
        values are the initial guess and, after a solve, the solution.
    bcs : sequence of dolfinx DirichletBCs
        On any of the bodies' spaces; their current values are written into :attr:`x` by
        :meth:`apply_bcs`, and their rows are constrained.
    contacts : sequence of NodeToSurface
        Pairs built with ``spaces`` = the bodies' spaces in this order (the default for a
        pair whose slave and master are the first bodies).
    jacobians : sequence of ufl.Form or None, optional
        Jacobian forms per body (None: ``ufl.derivative(F_i, u_i)``).
    obstacles : int
        Rigid obstacles whose translations are unknowns (pairs built with ``n_obstacles``
        = this and their ``obstacle_index``); their rows get the contact forces minus
        :attr:`f_ext`, or are constrained (:meth:`prescribe`).
    names : sequence of str, optional
        The bodies' names in messages (default: body 0, body 1, ...).
    """

    def __init__(self, residuals: Sequence[ufl.Form], u: Sequence, bcs: Sequence = (),
                 contacts: Sequence[NodeToSurface] = (),
                 jacobians: Optional[Sequence[Optional[ufl.Form]]] = None,
                 obstacles: int = 0, names: Optional[Sequence[str]] = None):
        if len(residuals) != len(u):
            raise ContactSetupError(f"{len(residuals)} residual forms for {len(u)} bodies")
        self.spaces = [w.function_space for w in u]
        self.comm = self.spaces[0].mesh.comm
        self.gdim = self.spaces[0].mesh.geometry.dim
        for V in self.spaces:
            if V.dofmap.index_map_bs != self.gdim:
                raise ContactSetupError("every body needs a vector space of the mesh dimension")
        for c in contacts:
            if len(c.spaces) != len(self.spaces) or any(
                    a is not b for a, b in zip(c.spaces, self.spaces)):
                raise ContactSetupError(f"{c.name}: built on other spaces than the problem's "
                                        f"bodies (pass spaces=[...] in the bodies' order)")
            if c.layout.n_global != DofLayout(
                    self.comm, [V.dofmap.index_map for V in self.spaces], obstacles).n_global:
                raise ContactSetupError(f"{c.name}: built for another number of obstacles")
        self.bcs, self.contacts, self.n_obstacles = list(bcs), list(contacts), obstacles
        jacobians = jacobians or [None] * len(u)
        self.bodies = [_Body(F, w, J, [bc for bc in bcs
                                       if compat.bc_on_space(bc, w.function_space)])
                       for F, w, J in zip(residuals, u, jacobians)]
        self.layout = DofLayout(self.comm, [V.dofmap.index_map for V in self.spaces], obstacles)
        n = self.layout.n_owned * self.gdim
        self.x = PETSc.Vec().createMPI((n, PETSc.DETERMINE), comm=self.comm)
        self.b = self.x.duplicate()
        self._scale = self.x.duplicate()
        #: external forces on the owned rows (loads on the bodies, forces on obstacles)
        self.f_ext = np.zeros(n)
        #: the rows' internal forces (residual + f_ext, before constraining) at the last
        #: evaluation: reactions are their sums over the constrained rows of a group
        self.internal = np.zeros(n)
        self._forces = np.zeros(3)  # squared norms: reactions, external, contact forces
        self.timers = Timers()
        self._bc_rows = self._dolfinx_bc_rows()
        self._prescribed_rows = np.zeros(0, dtype=np.int64)
        self._prescribed_values = np.zeros(0)
        self._constrained = self._bc_rows
        self.gather()
        self._base, values = self._bulk_pattern()
        self._motions = self._rigid_motions(names)
        self._linear_data = {k: self._base.gather_values(k, values[k])
                             for k, body in enumerate(self.bodies) if body.linear}
        #: bodies whose residual dolfinx assembles (the others are K u)
        self._assembled = [k for k, body in enumerate(self.bodies) if not body.homogeneous]
        self._K_linear: Optional[PETSc.Mat] = None
        if len(self._assembled) < len(self.bodies):
            self._K_linear = self._base.create_matrix()
            self._base.fill(self._K_linear, sum(self._linear_data[k] for k, body
                                                in enumerate(self.bodies) if body.homogeneous))
        self._pattern: Optional[CooPattern] = None
        self._versions: Optional[list[int]] = None
        self._J: Optional[PETSc.Mat] = None
        self._abs: Optional[PETSc.Mat] = None  # |J_bulk|, for the round-off floor
        self._abs_data: Optional[np.ndarray] = None
        self._bulk_data: Optional[np.ndarray] = None  # bulk Jacobian values (last, or constant)
        self._zeroed: Optional[tuple] = None  # (key, slots of the constrained rows, columns)
        self._static: Optional[tuple] = None  # (key, free obstacle rows, Jacobian without contact)
        self._coupling_slots: Optional[tuple] = None  # (key, contacts' slots, zeroed ones)
        self._bulk_bc: Optional[tuple] = None  # (constrained rows, bulk matrix with them)
        self._surface_dofs: Optional[np.ndarray] = None  # of all contacts (fixed in serial)
        self._modes: Optional[PETSc.NullSpace] = None
        self._floor: Optional[float] = 0.0  # of the last residual; None: not computed yet
        self._floor_x = self.x  # the iterate of the last residual
        self._spring = 0.0
        self._symmetric_bodies: Optional[bool] = None
        #: checks of an iterate (collective), each returning why it is inadmissible or None;
        #: the residual of an inadmissible iterate is infinite (Newton fails, and cuts back)
        self.guards: list = []
        #: why the last evaluated iterate was inadmissible ("" if it was not)
        self.inadmissible = ""

    @property
    def linear(self) -> bool:
        """Whether every body is linear (only the contact changes the Jacobian)."""
        return all(b.linear for b in self.bodies)

    @property
    def symmetric(self) -> bool:
        """Whether the Jacobian is symmetric once its constrained rows and columns are
        eliminated (``jacobian(x, symmetric=True)``): every body linear with a symmetric
        stiffness (checked once, to :data:`SYMMETRY_TOL`; collective) and every contact's
        tangent symmetric (:attr:`NodeToSurface.symmetric`: frictionless, its force derives
        from a potential, contact-theory 7.4)."""
        return self._bodies_symmetric() and all(c.symmetric for c in self.contacts)

    def _bodies_symmetric(self) -> bool:
        if self._symmetric_bodies is None:
            self._symmetric_bodies = self.linear and all(
                body.A.isSymmetric(SYMMETRY_TOL * body.A.norm(PETSc.NormType.NORM_INFINITY))
                for body in self.bodies)
        return self._symmetric_bodies

    # ------------------------------------------------------------ numbering
    def block_slice(self, k: int) -> slice:
        """Body ``k``'s owned dofs in this rank's part of :attr:`x`."""
        return self.layout.owned_slice(k, self.gdim)

    def obstacle_rows(self, k: int) -> np.ndarray:
        """(gdim,) local rows of obstacle ``k``'s translation on rank 0; empty elsewhere."""
        if self.comm.rank != 0:
            return np.zeros(0, dtype=np.int64)
        node = self.layout.rigid_node(k) - self.layout.start
        return node * self.gdim + np.arange(self.gdim)

    def scatter(self, x: Optional[PETSc.Vec] = None) -> None:
        """Copy the block vector (default :attr:`x`) into the bodies' Functions."""
        values = (self.x if x is None else x).getArray(readonly=True)
        for k, body in enumerate(self.bodies):
            body.u.x.array[: body.n_owned] = values[self.block_slice(k)]
            compat.scatter_forward(body.u)

    def gather(self) -> None:
        """Copy the bodies' Functions into :attr:`x`."""
        values = self.x.getArray()
        for k, body in enumerate(self.bodies):
            values[self.block_slice(k)] = body.u.x.array[: body.n_owned]
        self.x.setArray(values)

    def _dolfinx_bc_rows(self) -> np.ndarray:
        rows = []
        for k, body in enumerate(self.bodies):
            start = self.block_slice(k).start
            rows += [start + compat.bc_local_dofs(bc, body.n_owned) for bc in body.bcs]
        return np.unique(np.concatenate(rows)) if rows else np.zeros(0, dtype=np.int64)

    def reaction(self, where) -> np.ndarray:
        """The force (gdim,) [force] that holds a body at the dofs of ``where``: a
        Dirichlet condition (a condition on a subspace gives its components only) or a
        facet group ``Surface(V, tags, value)`` (its facets' dofs, e.g. part of a held
        edge; zero at convergence where nothing holds them).  The sum over those dofs of
        :attr:`internal` minus the external forces at the last residual evaluation, each
        dof counted once, by the rank that owns it.  Collective."""
        for k, body in enumerate(self.bodies):
            if isinstance(where, Surface):
                if where.V is not body.V:
                    continue
                fdim = body.V.mesh.topology.dim - 1
                nodes = compat.locate_nodes(body.V, fdim, compat.tagged(where.tags, where.value))
                nodes = nodes[nodes < body.n_owned // self.gdim]
                dofs = (nodes[:, None] * self.gdim + np.arange(self.gdim)).ravel()
            elif compat.bc_on_space(where, body.V):
                dofs = compat.bc_local_dofs(where, body.n_owned)
            else:
                continue
            total = np.zeros(self.gdim)
            rows = self.block_slice(k).start + dofs
            np.add.at(total, dofs % self.gdim, self.internal[rows] - self.f_ext[rows])
            return self.comm.allreduce(total)
        what = "facet group" if isinstance(where, Surface) else "condition"
        raise ContactSetupError(f"reaction: the {what} is on none of the problem's bodies")

    # ------------------------------------------------------------ constraints
    def prescribe(self, rows: np.ndarray, values: np.ndarray) -> None:
        """Constrain owned rows (local indices of :attr:`x`) to values, besides the
        dolfinx bcs; :meth:`apply_bcs` writes them into :attr:`x`."""
        rows = np.asarray(rows, dtype=np.int64)
        if not np.array_equal(rows, self._prescribed_rows):
            self._prescribed_rows = rows
            self._constrained = np.union1d(self._bc_rows, rows)
        self._prescribed_values = np.asarray(values, dtype=float)

    @property
    def constrained_rows(self) -> np.ndarray:
        """Local rows of :attr:`x` held by the bcs and :meth:`prescribe` (sorted)."""
        return self._constrained

    def apply_bcs(self) -> None:
        """Write the current values of the Dirichlet conditions into :attr:`x`."""
        if self.bcs:
            self.scatter()
            for body in self.bodies:
                compat.set_bc_values(compat.petsc_vector(body.u), body.bcs)
            self.gather()
        if len(self._prescribed_rows):
            values = self.x.getArray()
            values[self._prescribed_rows] = self._prescribed_values
            self.x.setArray(values)

    def free_obstacle_rows(self) -> np.ndarray:
        rows = np.concatenate([self.obstacle_rows(k) for k in range(self.n_obstacles)]
                              + [np.zeros(0, np.int64)])
        return np.setdiff1d(rows, self._prescribed_rows)

    # ------------------------------------------------------------ assembly
    def _bulk_pattern(self) -> tuple[CooPattern, list[np.ndarray]]:
        """The pattern of the bodies' Jacobians in the block numbering, and each body's
        CSR values at its current ``u`` (assembled once for both)."""
        d = self.gdim
        blocks, values = [], []
        for k, body in enumerate(self.bodies):
            compat.assemble_matrix_into(body.A, body.J)  # a new matrix: zero before
            indptr, cols, data = body.A.getValuesCSR()
            values.append(data)
            rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
            cols = cols.astype(np.int64)
            blocks.append((self.layout.nodes(k)[rows // d] * d + rows % d,
                           self.layout.from_block_global(k, cols // d) * d + cols % d))
        return CooPattern(self.comm, self.layout.n_owned * d, blocks), values

    def residual(self, x: PETSc.Vec, b: PETSc.Vec) -> float:
        """``b = R(x)``: the bodies' residuals minus :attr:`f_ext` plus the contact forces
        at their last :meth:`NodeToSurface.update`, zero in constrained rows.  Also sets
        :attr:`internal`; returns ``|b|`` (infinite, ``b`` untouched, when a guard finds the
        iterate inadmissible).  :meth:`roundoff_floor` is this residual's round-off."""
        self._floor = 0.0
        with self.timers.measure("bulk_assembly"):
            if self._assembled:
                self.scatter(x)
            self.inadmissible = next((r for r in (g() for g in self.guards) if r), "")
            if self.inadmissible:
                return np.inf
            if self._K_linear is not None:  # the homogeneous linear bodies: K u
                self._K_linear.mult(x, b)
                values = b.getArray()
            else:
                values = np.zeros(self.layout.n_owned * self.gdim)
            for k in self._assembled:
                values[self.block_slice(k)] += self.bodies[k].residual()
            values -= self.f_ext
            b.setArray(values)
        with self.timers.measure("contact_assembly"):
            for c in self.contacts:
                c.add_residual(b)
        r = b.getArray()
        self.internal = r + self.f_ext
        self._forces = np.array([self.internal[self.constrained_rows] @ self.internal[
            self.constrained_rows], self.f_ext @ self.f_ext, (r - values) @ (r - values)])
        r[self.constrained_rows] = 0.0
        b.setArray(r)
        norm = b.norm()
        if np.isfinite(norm):
            self._floor, self._floor_x = None, x  # computed on demand
        return norm

    def force_scale(self) -> float:
        """The size of the forces at the last :meth:`residual` (collective): the largest of
        the 2-norms of the reactions (the internal forces of the constrained rows), the
        external forces and the contact forces [force].  What the residual is small against
        (:class:`~dolfinx_friction.Newton`'s target and :meth:`postcondition`)."""
        return float(np.sqrt(self.comm.allreduce(self._forces).max()))

    def imbalance(self) -> np.ndarray:
        """(bodies + obstacles, gdim) the force left unbalanced on each body and obstacle at
        the last :meth:`residual`, summed over all ranks (collective) [force]: the sum of
        its residual over its free rows.  For a body whose form holds only internal forces
        (its nodal internal forces sum to zero) that is the sum of the reactions of its
        constraints, its external loads and the forces the contact pairs transmit to it;
        a load written into the form counts as external."""
        d = self.gdim
        r = self.b.getArray(readonly=True).reshape(-1, d)
        offsets = self.layout.block_offsets
        sums = np.zeros((len(self.bodies) + self.n_obstacles, d))
        for k in range(len(self.bodies)):
            sums[k] = r[offsets[k]:offsets[k + 1]].sum(axis=0)
        for j in range(self.n_obstacles):
            rows = self.obstacle_rows(j)
            if len(rows):
                sums[len(self.bodies) + j] = self.b.getArray(readonly=True)[rows]
        return self.comm.allreduce(sums)

    def free_rows(self) -> np.ndarray:
        """(bodies + obstacles, gdim) the number of free (unconstrained) rows of each body
        and obstacle per direction, over all ranks (collective)."""
        d, offsets = self.gdim, self.layout.block_offsets
        free = np.ones(self.layout.n_owned * d, dtype=bool)
        free[self.constrained_rows] = False
        free = free.reshape(-1, d)
        counts = np.zeros((len(self.bodies) + self.n_obstacles, d), dtype=np.int64)
        for k in range(len(self.bodies)):
            counts[k] = free[offsets[k]:offsets[k + 1]].sum(axis=0)
        for j in range(self.n_obstacles):
            rows = self.obstacle_rows(j)
            if len(rows):
                counts[len(self.bodies) + j] = free.reshape(-1)[rows]
        return self.comm.allreduce(counts)

    def postcondition(self, tolerance: float) -> str:
        """Why the state of the last :meth:`residual` is not an answer, or "" (collective;
        the contacts as at their last update): a body or obstacle whose unbalanced force
        (:meth:`imbalance`) along an axis exceeds ``sqrt(n) tolerance``, with n its free
        rows along that axis and ``tolerance`` the residual norm the convergence test
        accepts (the bound a converged residual keeps: Cauchy-Schwarz), or a slave node
        whose friction force exceeds mu times its normal force (by more than round-off).
        :func:`~dolfinx_friction.solve_steps` cuts back an increment that fails it."""
        imbalance, allowed = np.abs(self.imbalance()), np.sqrt(self.free_rows()) * tolerance
        ratio = np.divide(imbalance, allowed, out=np.where(imbalance > 0, np.inf, 0.0),
                          where=allowed > 0)
        k, axis = np.unravel_index(np.argmax(ratio), ratio.shape)
        if ratio[k, axis] > 1.0:
            n_bodies = len(self.bodies)
            who = (f"body {self.names[k]}" if k < n_bodies else f"obstacle {k - n_bodies}")
            return (f"{who} unbalanced by {imbalance[k, axis]:.3e} along "
                    f"{'xyz'[axis]} (allowed {allowed[k, axis]:.3e})")
        for c in self.contacts:
            excess = self.comm.allreduce(c.coulomb_excess(), op=MPI.MAX)
            if excess > 0.0:
                return (f"{c.name}: a friction force exceeds mu times its normal force by "
                        f"{excess:.3e}")
        return ""

    def roundoff_floor(self) -> float:
        """The round-off of the last :meth:`residual`'s norm (collective): 2 eps times the
        norm of ``|J_bulk| |x| + |f_ext|`` plus the contacts' terms over the free rows; no
        tolerance can ask for less.  0 after an inadmissible or non-finite residual (never a
        reason to accept it).  Computed on the first call after each residual."""
        if self._floor is None:
            with self.timers.measure("bulk_assembly"):
                self._scale_of_bulk(self._floor_x)
            with self.timers.measure("contact_assembly"):
                for c in self.contacts:
                    c.add_roundoff(self._scale)
                self._scale.assemble()
            scale = self._scale.getArray(readonly=True).copy()
            scale[self.constrained_rows] = 0.0
            floor = ROUNDOFF_FLOOR * np.sqrt(self.comm.allreduce(float(scale @ scale)))
            self._floor = floor if np.isfinite(floor) else 0.0
        return self._floor

    def _scale_of_bulk(self, x: PETSc.Vec) -> None:
        """``|J_bulk| |x| + |f_ext|`` into the round-off scale (contacts add theirs); a
        nonlinear body's ``J`` is the one of the last :meth:`jacobian`."""
        if self._abs is None or self._abs_data is not self._bulk_data:
            if self._bulk_data is None:
                self._bulk_data = self._bulk_values()
            if self._abs is None:
                self._abs = self._base.create_matrix()
            self._base.fill(self._abs, np.abs(self._bulk_data))
            self._abs_data = self._bulk_data
        ax = x.copy()
        ax.abs()
        self._abs.mult(ax, self._scale)
        ax.destroy()
        self._scale.setArray(self._scale.getArray() + np.abs(self.f_ext))

    def _bulk_values(self) -> np.ndarray:
        """Values of the bodies' Jacobians at their current ``u``, in the bulk pattern."""
        base = np.zeros(self._base.nnz)
        for k, body in enumerate(self.bodies):
            base += (self._linear_data[k] if body.linear
                     else self._base.gather_values(k, body.jacobian_values()))
        return base

    def matrix(self) -> PETSc.Mat:
        """The Jacobian matrix for the current contact couplings (a new one when they
        changed since the last call; collective).  It carries the block size and the
        bodies' rigid-body modes as near null space (for algebraic multigrid)."""
        versions = [c.couplings_version for c in self.contacts]
        if self._J is None or versions != self._versions:
            self._pattern = self._base.extended([c.couplings() for c in self.contacts])
            if self._J is not None:
                self._J.destroy()
            self._J = self._pattern.create_matrix(self.gdim)
            self._J.setNearNullSpace(self.rigid_body_modes())
            for c in self.contacts:
                c.register_matrix(self._J)
            self._versions = versions
        return self._J

    def jacobian(self, x: PETSc.Vec, A: Optional[PETSc.Mat] = None,
                 symmetric: bool = False) -> PETSc.Mat:
        """Fill the Jacobian at ``x`` (the contacts at their last update) into ``A``
        (default :meth:`matrix`); returns it.  ``symmetric``: the constrained columns are
        zeroed too (symmetric where :attr:`symmetric`); a Newton step is the same, since the
        residual is zero in the constrained rows."""
        with self.timers.measure("bulk_assembly"):
            A = self.matrix() if A is None else A
            if not self.linear:
                self.scatter(x)
            if self._bulk_data is None or not self.linear:
                self._bulk_data = self._bulk_values()
            base = self._bulk_data
        with self.timers.measure("contact_assembly"):
            static = self._static_values(base, symmetric)
            slots, values = self._contact_values(static, symmetric)
            self._pattern.fill_over(A, static, slots, values)
        return A

    def _static_values(self, base: np.ndarray, symmetric: bool) -> np.ndarray:
        """CSR data (pattern of :meth:`matrix`) of the Jacobian without contact: the bulk
        ``base``, the constrained rows (``symmetric``: and columns) zero but for a unit
        diagonal, the obstacles' springs.  Kept while pattern, ``base`` and rows are the
        same objects and the free obstacle rows the same (linear bodies: once per search)."""
        rows, free = self.constrained_rows, self.free_obstacle_rows()
        key = (self._pattern, base, rows, symmetric)
        cached = self._static
        if cached is not None and _same(cached[0], key) and np.array_equal(cached[1], free):
            return cached[2]
        data = self._pattern.from_base(base)
        data[self._zeroed_slots(rows, symmetric)] = 0.0
        # A force-controlled obstacle may have no stiffness along some axis (a
        # frictionless plane in its own plane): a tiny spring in the Jacobian only keeps
        # it regular; the residual, hence the solution, is unchanged.
        data[self._pattern.diagonal_slots[free]] += self._rigid_spring(base)
        data[self._pattern.diagonal_slots[rows]] = 1.0
        self._static = (key, free, data)
        return data

    def _zeroed_slots(self, rows: np.ndarray, symmetric: bool) -> np.ndarray:
        """CSR slots of the constrained ``rows`` (``symmetric``: and of their columns on
        every rank; collective), kept with the pattern and the rows."""
        key = (self._pattern, rows, symmetric)
        cached = self._zeroed
        if cached is None or not _same(cached[0], key):
            columns = (np.concatenate(self.comm.allgather(self._global_rows(rows)))
                       if symmetric else None)
            self._zeroed = cached = (key, self._pattern.row_slots(rows, columns))
        return cached[1]

    def _contact_values(self, static: np.ndarray, symmetric: bool
                        ) -> tuple[np.ndarray, np.ndarray]:
        """The slots of the contacts' couplings (kept with the pattern) and the Jacobian's
        values there: ``static`` plus the contacts' tangents, but in the constrained rows
        (``symmetric``: and columns)."""
        rows = self.constrained_rows
        gathered = [self._pattern.gather_slots(k, c.coupling_values())
                    for k, c in enumerate(self.contacts)]
        key = (self._pattern, rows, symmetric)
        cached = self._coupling_slots
        if cached is None or not _same(cached[0], key):
            slots = np.unique(np.concatenate([at for at, _ in gathered]
                                             + [np.zeros(0, np.int64)]))
            zeroed = np.isin(slots, self._zeroed_slots(rows, symmetric))
            self._coupling_slots = cached = (key, slots, zeroed)
        _, slots, zeroed = cached
        contact = np.zeros(len(slots))
        for at, sums in gathered:
            contact[np.searchsorted(slots, at)] += sums
        contact[zeroed] = 0.0
        return slots, static[slots] + contact

    def _global_rows(self, rows: np.ndarray) -> np.ndarray:
        """Global indices of owned local rows."""
        return (rows + self.x.getOwnershipRange()[0]).astype(PETSc.IntType)

    def split(self) -> Optional["JacobianSplit"]:
        """The Jacobian at the contacts' last update as a constant bulk matrix plus a
        contact part supported on the contact surfaces (no matrix is filled), or None where
        that split does not hold or is not implemented: a body that is not linear, rigid
        obstacles (their rows have no bulk stiffness), several ranks (the contact entries
        and dofs are local indices)."""
        if not self.linear or self.n_obstacles or self.comm.size > 1 or not self.contacts:
            return None
        rows = self.constrained_rows
        with self.timers.measure("bulk_assembly"):
            if self._bulk_bc is None or self._bulk_bc[0] is not rows:
                if self._bulk_bc is not None:
                    self._bulk_bc[1].destroy()
                data = (self._bulk_values() if self._bulk_data is None
                        else self._bulk_data.copy())
                data[self._base.row_slots(rows)] = 0.0
                data[self._base.diagonal_slots[rows]] = 1.0
                K = self._base.create_matrix(self.gdim)
                self._base.fill(K, data)
                if self._bodies_symmetric():
                    K.zeroRowsColumns(self._global_rows(rows), diag=1.0)
                self._bulk_bc = (rows, K)
        with self.timers.measure("contact_assembly"):
            free = np.ones(self.layout.n_owned * self.gdim, bool)
            free[rows] = False
            entries = [c.element_entries() for c in self.contacts]
            r, k, v = (np.concatenate(e) for e in zip(*entries))
            keep = (v != 0.0) & free[r]
            if self._bodies_symmetric():  # the constrained columns eliminated, as in K
                keep &= free[k]
            if self._surface_dofs is None:
                self._surface_dofs = np.unique(np.concatenate(
                    [c.surface_dofs() for c in self.contacts]))
        return JacobianSplit(self._bulk_bc[1], self._surface_dofs, r[keep], k[keep], v[keep],
                             self._bodies_symmetric())

    def _rigid_spring(self, base: np.ndarray) -> float:
        """1e-12 of the largest bulk diagonal entry (found once)."""
        if not self._spring and self.n_obstacles:
            diagonal = np.abs(base[self._base.diagonal_slots])
            self._spring = 1e-12 * self.comm.allreduce(float(diagonal.max(initial=0.0)),
                                                       op=MPI.MAX)
        return self._spring

    def _rigid_motions(self, names: Optional[Sequence[str]]) -> RigidMotions:
        """The bodies' rigid motions, with what their own Jacobians (just assembled at the
        initial displacement) hold of them (collective)."""
        X = [V.tabulate_dof_coordinates()[: V.dofmap.index_map.size_local, : self.gdim]
             for V in self.spaces]
        #: (owned nodes, gdim) reference coordinates of this rank's nodes (0 for obstacles)
        self._X = np.concatenate(X + [np.zeros((self.layout.n_owned - sum(map(len, X)),
                                                self.gdim))])
        labels = ([repr(str(n)) for n in names] if names is not None
                  else [str(k) for k in range(len(self.bodies))])
        #: the bodies' names in messages (quoted) or numbers
        self.names = labels
        motions = RigidMotions(self.comm, X, self.n_obstacles, labels)
        for k, body in enumerate(self.bodies):
            motions.add_stiffness(k, body.A, X[k])
        return motions

    def check_held(self) -> None:
        """Raise :class:`~dolfinx_friction.ContactSetupError` (one line naming the body and
        the motion, on every rank) where a body can move rigidly with nothing to hold it
        now: no constrained row, no closed contact node (along its normal if frictionless,
        in every direction with friction) and no stiffness of the body's own form (a
        spring) resists the motion, so that a converged solution may carry any amount of
        it (:mod:`dolfinx_friction.fem.rigid_motions`).  Collective; the contacts as at their last
        update.  :class:`~dolfinx_friction.Newton` and :func:`~dolfinx_friction.snes_solve`
        call it on convergence."""
        d, motions, offsets = self.gdim, self._motions, self.layout.block_offsets
        n_bodies = len(self.bodies)
        x = self._X + self.x.getArray(readonly=True).reshape(-1, d)  # current coordinates
        motions.move([x[offsets[k]:offsets[k + 1]] for k in range(n_bodies)])
        rows = self.constrained_rows
        nodes = rows // d
        owner = np.searchsorted(offsets, nodes, side="right") - 1
        obstacle = owner == n_bodies  # obstacle j is owner n_bodies + j
        owner[obstacle] += nodes[obstacle] - offsets[n_bodies]
        holding = [motions.rows(owner, x[nodes], np.eye(d)[rows % d])]
        for c in self.contacts:
            s = c.support()
            other = (s.master if s.master is not None
                     else None if s.obstacle is None else n_bodies + s.obstacle)
            for e in ([np.tile(e, (len(s.x), 1)) for e in np.eye(d)] if s.frictional
                      else [s.normal]):
                relative = motions.rows(s.slave, s.x, e)
                if other is not None:
                    relative -= motions.rows(other, s.x, e)
                holding.append(relative)
        message = motions.unheld(holding)
        if message:
            raise ContactSetupError(message)

    def rigid_body_modes(self) -> PETSc.NullSpace:
        """Translations and rotations of every body, orthonormal (collective): the near null
        space of elasticity for algebraic multigrid.  An obstacle only translates."""
        if self._modes is not None:
            return self._modes
        d = self.gdim
        modes = [self.x.duplicate() for _ in range(3 if d == 2 else 6)]
        values = np.zeros((len(modes), self.x.getLocalSize() // d, d))
        for k, V in enumerate(self.spaces):
            nodes = slice(int(self.layout.block_offsets[k]), int(self.layout.block_offsets[k + 1]))
            X = V.tabulate_dof_coordinates()[: V.dofmap.index_map.size_local, :d]
            values[:d, nodes] = np.eye(d)[:, None, :]
            for j, (a, c) in enumerate([(0, 1)] if d == 2 else [(0, 1), (1, 2), (2, 0)]):
                values[d + j, nodes, a], values[d + j, nodes, c] = -X[:, c], X[:, a]
        for k in range(self.n_obstacles):
            values[:d, self.obstacle_rows(k)[:1] // d] = np.eye(d)[:, None, :]
        for k, mode in enumerate(modes):  # modified Gram-Schmidt
            mode.setArray(values[k].ravel())
            for previous in modes[:k]:
                mode.axpy(-mode.dot(previous), previous)
            mode.scale(1.0 / mode.norm())
        self._modes = PETSc.NullSpace().create(vectors=modes, comm=self.comm)
        return self._modes
