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

from typing import Optional, Sequence

import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx_friction import _compat as compat
from dolfinx_friction.fem.body_forms import BodyForms
from dolfinx_friction.fem.jacobian import BlockJacobian, JacobianSplit
from dolfinx_friction.fem.rigid_motions import RigidMotions
from dolfinx_friction.fem.numbering import DofLayout
from dolfinx_friction.fem.timers import Timers
from dolfinx_friction.fem.node_to_surface import ContactSetupError, NodeToSurface, Surface

#: Residual norms below this many round-off units of the terms they sum (|J| |x| + |f_ext|
#: + the contact forces' sensitivity to the coordinates) are converged: Newton cannot
#: reduce them further.
ROUNDOFF_FLOOR = 2 * np.finfo(float).eps
#: A body's stiffness is symmetric when no entry differs from its transpose's by more than
#: this share of the largest row sum (compiled forms sum in another order: round-off)
SYMMETRY_TOL = 1e-12


class BlockProblem:
    """Residual and Jacobian of several bodies with contact, in one block numbering.

    Parameters
    ----------
    residuals : sequence of ufl.Form or BodyForms
        One UFL residual form per body, ``F_i(u_i; v_i)`` (internal minus external virtual
        work), linear in the test function; or the body's forms compiled already (a
        :class:`~dolfinx_friction.fem.body_forms.BodyForms` of ``u_i``, without bcs; its
        Jacobian is its own).
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
        self.bodies = [self._body_forms(F, w, J) for F, w, J in zip(residuals, u, jacobians)]
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
        self._interior: Optional[tuple] = None  # (constrained rows, linear_interior())
        self.gather()
        #: bodies whose residual dolfinx assembles (the others are K u)
        self._assembled = [k for k, body in enumerate(self.bodies) if not body.homogeneous]
        #: the Jacobian's matrix and caches (assembles the bodies' Jacobians: before the
        #: rigid motions, which read them)
        self.jacobians = BlockJacobian(self, [k for k, body in enumerate(self.bodies)
                                              if body.homogeneous])
        self._motions = self._rigid_motions(names)
        self._floor: Optional[float] = 0.0  # of the last residual; None: not computed yet
        self._floor_x = self.x  # the iterate of the last residual
        self._symmetric_bodies: Optional[bool] = None
        #: checks of an iterate (collective), each returning why it is inadmissible or None;
        #: the residual of an inadmissible iterate is infinite (Newton fails, and cuts back)
        self.guards: list = []
        #: checks of the same kind run only when the residual is not finite, to say why
        #: (for a model whose residual is not finite wherever the check fails)
        self.nonfinite_guards: list = []
        #: why the last evaluated iterate was inadmissible ("" if it was not)
        self.inadmissible = ""

    def _body_forms(self, F, u, J: Optional[ufl.Form]) -> BodyForms:
        """A body's compiled forms (those given, checked against ``u`` and the bcs)."""
        bcs = [bc for bc in self.bcs if compat.bc_on_space(bc, u.function_space)]
        if not isinstance(F, BodyForms):
            return BodyForms(F, u, J, bcs)
        if F.u is not u or bcs or J is not None:
            raise ContactSetupError("compiled body forms are given for their own u, without "
                                    "bcs on its space and without a Jacobian form")
        return F

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
        return self.bodies_symmetric() and all(c.symmetric for c in self.contacts)

    def bodies_symmetric(self) -> bool:
        """Whether every body is linear with a symmetric stiffness (checked once, to
        :data:`SYMMETRY_TOL`; collective)."""
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
        dolfinx bcs; :meth:`apply_bcs` writes them into :attr:`x`.  Collective: where the
        rows changed on any rank, :attr:`constrained_rows` is a new array on every rank
        (the caches keyed on it are collective)."""
        rows = np.asarray(rows, dtype=np.int64)
        if self.comm.allreduce(not np.array_equal(rows, self._prescribed_rows), op=MPI.LOR):
            self._prescribed_rows = rows
            self._constrained = np.union1d(self._bc_rows, rows)
        self._prescribed_values = np.asarray(values, dtype=float)

    def linear_interior(self) -> np.ndarray:
        """Local rows whose rows and columns of the Jacobian are the same for the whole run:
        the free dofs of the linear bodies off every contact surface (sorted).  Serial with
        a body that is not linear and a contact (where every body is linear the Jacobian
        splits instead: :meth:`split`); empty otherwise."""
        if self.comm.size > 1 or self.linear or not self.contacts:
            return np.zeros(0, dtype=np.int64)
        if self._interior is None or self._interior[0] is not self._constrained:
            rows = np.concatenate([np.arange(self.block_slice(k).start,
                                             self.block_slice(k).stop)
                                   for k, body in enumerate(self.bodies) if body.linear]
                                  + [np.zeros(0, dtype=np.int64)])
            held = np.concatenate([c.surface_dofs() for c in self.contacts]
                                  + [self._constrained])
            self._interior = (self._constrained, np.setdiff1d(rows, held))
        return self._interior[1]

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
            parts = [(k, self.bodies[k].residual()) for k in self._assembled]
            if self.nonfinite_guards and self.comm.allreduce(
                    not all(np.isfinite(part).all() for _, part in parts), op=MPI.LOR):
                self.inadmissible = next(
                    (r for r in (g() for g in self.nonfinite_guards) if r), "")
                if self.inadmissible:
                    return np.inf
            K_linear = self.jacobians.K_linear
            if K_linear is not None:  # the homogeneous linear bodies: K u
                K_linear.mult(x, b)
                values = b.getArray()
            else:
                values = np.zeros(self.layout.n_owned * self.gdim)
            for k, part in parts:
                values[self.block_slice(k)] += part
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
        whose friction force exceeds mu times its normal force (by more than round-off), or
        a contact that converged with stale pairings (:meth:`NodeToSurface.stale_pairing`).
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
            stale = c.stale_pairing()
            if stale:
                return (f"{c.name}: converged after its pairing froze; pairing at the "
                        f"converged state closes or opens {stale} slave node(s)")
        return ""

    def roundoff_floor(self) -> float:
        """The round-off of the last :meth:`residual`'s norm (collective): 2 eps times the
        norm of ``|J_bulk| |x| + |f_ext|`` plus the contacts' terms over the free rows; no
        tolerance can ask for less.  0 after an inadmissible or non-finite residual (never a
        reason to accept it).  Computed on the first call after each residual."""
        if self._floor is None:
            with self.timers.measure("bulk_assembly"):
                self.jacobians.scale_of_bulk(self._floor_x, self._scale)
            with self.timers.measure("contact_assembly"):
                for c in self.contacts:
                    c.add_roundoff(self._scale)
                self._scale.assemble()
            scale = self._scale.getArray(readonly=True).copy()
            scale[self.constrained_rows] = 0.0
            floor = ROUNDOFF_FLOOR * np.sqrt(self.comm.allreduce(float(scale @ scale)))
            self._floor = floor if np.isfinite(floor) else 0.0
        return self._floor

    def matrix(self) -> PETSc.Mat:
        """The Jacobian matrix for the current contact couplings (a new one when they
        changed since the last call; collective): :meth:`BlockJacobian.matrix`."""
        return self.jacobians.matrix()

    def jacobian(self, x: PETSc.Vec, A: Optional[PETSc.Mat] = None,
                 symmetric: bool = False) -> PETSc.Mat:
        """Fill the Jacobian at ``x`` (the contacts at their last update) into ``A``
        (default :meth:`matrix`); returns it.  ``symmetric``: the constrained columns are
        zeroed too (symmetric where :attr:`symmetric`); a Newton step is the same, since the
        residual is zero in the constrained rows."""
        return self.jacobians.jacobian(x, A, symmetric)

    def split(self) -> Optional[JacobianSplit]:
        """The Jacobian as a constant bulk matrix plus the contact entries, or None where
        that split does not hold (:meth:`BlockJacobian.split`)."""
        return self.jacobians.split()

    def normal_models(self) -> Optional[list]:
        """Every contact pair's elements at their last update as a
        :class:`~dolfinx_friction.fem.node_to_surface.NormalModel` (this rank's), or None
        where some pair has none (friction, a law that is not bilinear; collective)."""
        models = [c.normal_model() if hasattr(c, "normal_model") else None
                  for c in self.contacts]
        ok = bool(models) and all(m is not None for m in models)
        return models if self.comm.allreduce(int(not ok)) == 0 else None

    def rigid_body_modes(self) -> PETSc.NullSpace:
        """Translations and rotations of every body, orthonormal (collective): the near null
        space of elasticity for algebraic multigrid."""
        return self.jacobians.rigid_body_modes()

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

