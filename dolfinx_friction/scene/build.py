"""The discrete problem of a scene: bodies as UFL residuals, obstacles, contact pairs.

Built once from a :class:`~dolfinx_friction.scene.model.Scene` on the composable core, in
two stages: :class:`DiscreteScene` puts the scene on its mesh and validates it (spaces,
numbering, each ``[[contact]]`` a :class:`~dolfinx_friction.fem.node_to_surface.NodeToSurface`);
:class:`ContactProblem` adds the equations: each body's residual a UFL form of its own
dolfinx space, every ``[[rigid]]`` obstacle's translation an unknown of the
:class:`~dolfinx_friction.fem.block_problem.BlockProblem` that joins them.  The solver
drives it.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable, Optional, TypeVar

import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx_friction import _compat as compat

from dolfinx_friction.io import gmsh as gmsh_io
from dolfinx_friction.fem.axisymmetric import axisymmetric_grad, section_fault, section_weight
from dolfinx_friction.fem.contact_fields import nodal_fields
from dolfinx_friction.fem.materials import bulk_modulus, lame, out_of_plane
from dolfinx_friction.fem.numbering import BodyField, make_fields
from dolfinx_friction.fem.obstacles import Obstacle
from dolfinx_friction.scene import validation
from dolfinx_friction.scene.model import Body, ContactPair, Scene
from dolfinx_friction.scene.validation import ModelError
from dolfinx_friction.fem.node_to_surface import ContactSetupError, NodeToSurface, Surface, make_law
from dolfinx_friction.fem.block_problem import BlockProblem
from dolfinx_friction.fem.body_forms import BodyForms
from dolfinx_friction.scene.workspace import Workspace, file_key

T = TypeVar("T")


@dataclass
class SceneField(BodyField):
    """A body's field (:class:`~dolfinx_friction.fem.numbering.BodyField`) with the
    scene's :class:`~dolfinx_friction.scene.model.Body` it was made for (its material)."""

    body: Body

    @classmethod
    def of(cls, field: BodyField, body: Body) -> "SceneField":
        return cls(**{f.name: getattr(field, f.name) for f in dataclasses.fields(field)},
                   body=body)


def _lame(body: Body, gdim: int) -> tuple[float, float]:
    return lame(body.E, body.nu, plane_stress=gdim == 2 and body.plane == "stress")


def _thickness(field: BodyField):
    """The weight of ``dx`` and ``ds``: a plane body's thickness, ``2 pi r`` (UFL) on an
    axisymmetric body, 1 in 3D."""
    return section_weight(field)


def _grad(field: BodyField, w):
    """``grad w``, the 3 x 3 :func:`~dolfinx_friction.fem.axisymmetric.axisymmetric_grad`
    on an axisymmetric body."""
    return axisymmetric_grad(w) if field.axisymmetric else ufl.grad(w)


def _dx(field: BodyField) -> ufl.Measure:
    """Gauss rules of degree 2k for a rational integrand (finite strain, or ``u_r / r``):
    2 x 2 points on bilinear quadrilaterals, as CalculiX's CPE4 / CAX4 / C3D8."""
    return ufl.dx(metadata={"quadrature_degree": 2 * compat.space_degree(field.V)})


def elastic_forms(field: BodyField) -> tuple[ufl.Form, ufl.Form]:
    """Residual ``(sigma(u), eps(v)) t dx`` of small-strain linear elasticity and its
    Jacobian (``t``: the thickness of a 2D body; ``2 pi r`` and the hoop strain
    ``u_r / r`` on an axisymmetric one)."""
    lam, mu = _lame(field.body, field.gdim)
    v, du = ufl.TestFunction(field.V), ufl.TrialFunction(field.V)
    if field.axisymmetric:
        def eps3(w):
            return ufl.sym(axisymmetric_grad(w))

        def sigma3(w):
            return lam * ufl.tr(eps3(w)) * ufl.Identity(3) + 2.0 * mu * eps3(w)
        weight, dx = _thickness(field), _dx(field)
        return (weight * ufl.inner(sigma3(field.u), eps3(v)) * dx,
                weight * ufl.inner(sigma3(du), eps3(v)) * dx)

    def eps(w):
        return ufl.sym(ufl.grad(w))

    def sigma(w):
        return lam * ufl.tr(eps(w)) * ufl.Identity(field.gdim) + 2.0 * mu * eps(w)
    t = _thickness(field)
    return (t * ufl.inner(sigma(field.u), eps(v)) * ufl.dx,
            t * ufl.inner(sigma(du), eps(v)) * ufl.dx)


def deformation_gradient(u, gdim: int, axisymmetric: bool = False):
    """``(F, F3)``: the deformation gradient as a UFL variable, and as 3 x 3 (plane strain
    in 2D: ``F33 = 1``; axisymmetric: ``F_thetatheta = 1 + u_r / r``, and ``F`` is ``F3``)."""
    if axisymmetric:
        F = ufl.variable(ufl.Identity(3) + axisymmetric_grad(u))
        return F, F
    F = ufl.variable(ufl.Identity(gdim) + ufl.grad(u))
    if gdim == 3:
        return F, F
    return F, ufl.as_matrix([[F[0, 0], F[0, 1], 0], [F[1, 0], F[1, 1], 0], [0, 0, 1]])


def strain_energy(body: Body, F3):
    """Strain energy density per reference volume of a finite-strain model.

    Saint Venant-Kirchhoff: ``W = lam/2 tr(E)^2 + mu tr(E^2)``, ``E = (F^T F - I)/2``.
    Neo-Hooke (CalculiX's NEO HOOKE): ``W = C10 (I1bar - 3) + (J - 1)^2 / D1`` with
    ``I1bar = J^(-2/3) tr(F^T F)``, ``C10 = mu/2``, ``D1 = 2/kappa``, ``kappa = E/(3(1-2nu))``.
    """
    lam, mu = lame(body.E, body.nu)
    C = F3.T * F3
    if body.model == "saint-venant-kirchhoff":
        E = 0.5 * (C - ufl.Identity(3))
        return 0.5 * lam * ufl.tr(E) ** 2 + mu * ufl.inner(E, E)
    if body.model == "neo-hookean":
        kappa = bulk_modulus(body.E, body.nu)
        J = ufl.det(F3)
        return 0.5 * mu * (J ** (-2.0 / 3.0) * ufl.tr(C) - 3.0) + 0.5 * kappa * (J - 1.0) ** 2
    raise ValueError(f"body {body.name!r}: unknown model {body.model!r}")


def undefined_when_inverted(body: Body) -> bool:
    """Whether the body's residual is not finite wherever ``det F <= 0`` at a quadrature
    point (Neo-Hooke's ``J^(-2/3)``): its inversion guard need run only when it is not."""
    return body.model == "neo-hookean"


def cauchy_stress(field: BodyField):
    """The body's Cauchy stress as a 3 x 3 UFL tensor (plane strain in 2D: with the
    out-of-plane normal stress; axisymmetric: (r, z, theta))."""
    body, d = field.body, field.gdim
    if not body.finite_strain and field.axisymmetric:
        lam, mu = _lame(body, d)
        eps = ufl.sym(axisymmetric_grad(field.u))
        return lam * ufl.tr(eps) * ufl.Identity(3) + 2.0 * mu * eps
    if not body.finite_strain:
        lam, mu = _lame(body, d)
        eps = ufl.sym(ufl.grad(field.u))
        sigma = lam * ufl.tr(eps) * ufl.Identity(d) + 2.0 * mu * eps
        if d == 3:
            return sigma
        s33 = lam * ufl.tr(eps) if body.plane == "strain" else 0.0
        return ufl.as_matrix([[sigma[0, 0], sigma[0, 1], 0], [sigma[1, 0], sigma[1, 1], 0],
                              [0, 0, s33]])
    F, F3 = deformation_gradient(field.u, d, field.axisymmetric)
    F3v = ufl.variable(F3)
    P = ufl.diff(strain_energy(body, F3v), F3v)
    return P * F3.T / ufl.det(F3)


def von_mises(sigma):
    """``sqrt(3/2 s:s)`` of a 3 x 3 stress tensor, ``s`` its deviator."""
    s = sigma - ufl.tr(sigma) / 3.0 * ufl.Identity(3)
    return ufl.sqrt(1.5 * ufl.inner(s, s))


def body_forms(field: BodyField) -> tuple[ufl.Form, Optional[ufl.Form]]:
    """The body's residual form and Jacobian (None: ``ufl.derivative``): small-strain
    elasticity, or the first Piola-Kirchhoff stress ``P = dW/dF`` of its finite-strain
    model against the gradient of the test function (reference configuration)."""
    if not field.body.finite_strain:
        return elastic_forms(field)
    F, F3 = deformation_gradient(field.u, field.gdim, field.axisymmetric)
    P = ufl.diff(strain_energy(field.body, F3), F)
    v = ufl.TestFunction(field.V)
    # UFL would estimate a high degree for the rational integrand
    return _thickness(field) * ufl.inner(P, _grad(field, v)) * _dx(field), None


class DiscreteScene:
    """A scene on its mesh, validated: the bodies' spaces and the system numbering that
    joins them, and the contact pairs; no forms, no system (what ``check`` builds).

    ``pairs`` maps each contact's name (``"slave->master"``) to its
    :class:`NodeToSurface`.  Raises :class:`~dolfinx_friction.scene.validation.ModelError`
    (and the mesh loader's ``MeshError``) for a scene that does not fit its mesh or cannot
    be solved as given (:mod:`~dolfinx_friction.scene.validation`).
    """

    def __init__(self, scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD,
                 meshes: Optional[gmsh_io.MeshSet] = None,
                 workspace: Optional[Workspace] = None):
        self.scene, self.comm = scene, comm
        #: what this problem takes from and leaves to later runs (None: nothing shared)
        self.workspace = workspace if meshes is None else None
        names = [b.name for b in scene.bodies]
        mesh_key = None
        if self.workspace is not None:
            try:
                mesh_key = ("meshes", file_key(scene.mesh), tuple(names), comm.py2f())
            except (OSError, TypeError):  # (no such file: the loader says so)
                pass
        self.meshes = meshes or self.shared(
            mesh_key, lambda: gmsh_io.load_mesh(scene.mesh, names, comm))
        self.gdim = self.meshes.gdim
        validation.check_groups(scene, self.meshes)
        discretisation = (len(scene.rigids), tuple(b.degree for b in scene.bodies),
                          tuple(b.thickness for b in scene.bodies),
                          tuple(b.axisymmetric for b in scene.bodies))
        fields, self.layout = self.shared(
            mesh_key and ("fields", mesh_key, discretisation), lambda: make_fields(
                comm, [self.meshes.bodies[b.name] for b in scene.bodies], len(scene.rigids),
                degrees=[b.degree for b in scene.bodies],
                thicknesses=[b.thickness for b in scene.bodies],
                axisymmetric=[b.axisymmetric for b in scene.bodies]))
        for f in fields:  # (kept from another run: its displacement goes)
            f.u.x.array[:] = 0.0
        self.fields = [SceneField.of(f, b) for f, b in zip(fields, scene.bodies)]
        for i, f in enumerate(self.fields):
            fault = section_fault(f) if f.axisymmetric else ""
            if fault:
                raise ModelError(f"body.{i}.plane = \"axisymmetric\": body {f.body.name!r}: "
                                 f"{fault}")
        validation.check_solvable(scene)
        validation.check_held(scene, self.meshes.group_bodies)
        validation.check_bcs(scene, self.fields, self.meshes.group_bodies, comm)
        self.pairs = {f"{c.slave}->{c.master}": self._pair(c, f"contact.{i}")
                      for i, c in enumerate(scene.contacts)}

    def shared(self, key: Optional[tuple], make: Callable[[], T]) -> T:
        """``make()``, or the object the workspace kept for ``key`` (None: not shared); the
        key holds all the object depends on (an object by ``id``: the value holds it)."""
        if key is None or self.workspace is None:
            return make()
        return self.workspace.get(key, make)

    # ------------------------------------------------------------ lookups
    def body_field(self, name: str) -> SceneField:
        return next(f for f in self.fields if f.body.name == name)

    def group_fields(self, group: str) -> list[SceneField]:
        return [self.body_field(b) for b in self.meshes.group_bodies.get(group, ())]

    def rigid_node(self, name: str) -> int:
        return self.layout.rigid_node([r.name for r in self.scene.rigids].index(name))

    def owned_group_dofs(self, group: str) -> np.ndarray:
        """Local (rank-owned) system dof rows of every node of a group, (n_nodes, gdim)."""
        d = self.gdim
        rows = [(self.layout.block_offsets[f.block] + f.owned_group_nodes(group))[:, None] * d
                + np.arange(d) for f in self.group_fields(group)]
        return np.concatenate(rows) if rows else np.zeros((0, d), dtype=np.int64)

    def rigid_dofs(self, name: str) -> np.ndarray:
        """Local system dof rows of a rigid obstacle's translation (rank 0; empty elsewhere)."""
        if self.comm.rank != 0:
            return np.zeros((0, self.gdim), dtype=np.int64)
        node = self.rigid_node(name) - self.layout.start
        return (node * self.gdim + np.arange(self.gdim))[None]

    # ------------------------------------------------------------- contact
    def _pair(self, pair: ContactPair, key: str) -> NodeToSurface:
        slave_field = self.group_fields(pair.slave)[0]
        body = slave_field.body
        pair = pair.resolved(body.E)  # K and stick_slope: by NodeToSurface, with its spacing
        rigid = self.scene.rigid(pair.master)
        fdim = self.gdim - 1
        slave_tags, _ = slave_field.mesh.meshtags(fdim, [pair.slave])
        if rigid is not None:
            master = Obstacle.like(rigid)  # as given (rigid_plane would make unit vectors)
            index = [r.name for r in self.scene.rigids].index(rigid.name)
        else:
            master_field = self.group_fields(pair.master)[0]
            master = Surface(master_field.V, master_field.mesh.meshtags(fdim, [pair.master])[0], 1)
            index = None
        try:
            return NodeToSurface(
                Surface(slave_field.V, slave_tags, 1), master, spaces=[f.V for f in self.fields],
                law=None if pair.law == "linear" else make_law(pair), K=pair.K,
                sigma_inf=pair.sigma_inf, c0=pair.c0, E=body.E, mu=pair.mu,
                stick_slope=pair.stick_slope, tangent=pair.tangent,
                thickness=out_of_plane(body.thickness, self.gdim),
                axisymmetric=body.axisymmetric,
                pairing_iterations=pair.pairing_iterations, method=pair.method,
                augmented_tolerance=pair.augmented_tolerance,
                distribution=pair.distribution, name=f"{pair.slave}->{pair.master}",
                obstacle_index=index, n_obstacles=len(self.scene.rigids),
                body_names=(body.name, pair.master))
        except ContactSetupError as error:  # e.g. a default K that overflows
            raise ModelError(f"{key}: {error}") from None

    def pair_of(self, contact: ContactPair) -> NodeToSurface:
        """The :class:`NodeToSurface` of a scene contact."""
        return self.pairs[f"{contact.slave}->{contact.master}"]

    def contact_fields(self, field: BodyField) -> dict[str, np.ndarray]:
        """The nodal contact fields of a body (:func:`~dolfinx_friction.fem.contact_fields.
        nodal_fields`: the pairs whose slave surface is on it; owned nodes, ghosts empty)."""
        states = [self.pair_of(c).state() for c in self.scene.contacts
                  if self.group_fields(c.slave)[0] is field]
        return nodal_fields(states, len(field.X), self.gdim)


class ContactProblem(DiscreteScene):
    """A scene's bodies, obstacles and contact pairs as one :class:`BlockProblem`
    (``system``): a :class:`DiscreteScene` with its equations.

    ``system.x`` is the displacement (the only copy: the bodies' Functions are refreshed
    from it).
    """

    def __init__(self, scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD,
                 meshes: Optional[gmsh_io.MeshSet] = None,
                 workspace: Optional[Workspace] = None):
        super().__init__(scene, comm, meshes, workspace)
        self.follower_pressures = self._follower_pressures()
        self.system = BlockProblem([self._compiled(f) for f in self.fields],
                                   [f.u for f in self.fields],
                                   contacts=list(self.pairs.values()),
                                   obstacles=len(scene.rigids),
                                   names=[b.name for b in scene.bodies])
        for f in self.fields:
            if f.body.finite_strain:
                (self.system.nonfinite_guards if undefined_when_inverted(f.body)
                 else self.system.guards).append(self._inversion_guard(f))

    def _follower_pressures(self) -> dict[tuple[str, str], object]:
        """A Constant per (finite-strain body, group) that some step loads with a pressure:
        such a pressure follows the deformed face (its load stiffness is in the Jacobian)."""
        out = {}
        for step in self.scene.steps:
            for load in step.loads:
                if load.pressure is None:
                    continue
                for f in self.group_fields(load.on):
                    if f.body.finite_strain and (f.body.name, load.on) not in out:
                        out[(f.body.name, load.on)] = compat.scalar_constant(f.V.mesh, 0.0)
        return out

    def _compiled(self, field: SceneField) -> BodyForms:
        """A body's compiled forms; shared through the workspace (by its displacement and
        material) unless a follower pressure loads it (its Constant is this problem's)."""
        def compile_forms() -> BodyForms:
            F, J = self._forms(field)
            return BodyForms(F, field.u, J, [])
        followed = any(body == field.body.name for body, _ in self.follower_pressures)
        return self.shared(None if followed else ("forms", id(field.u), field.body),
                            compile_forms)

    def _forms(self, field: BodyField) -> tuple[ufl.Form, Optional[ufl.Form]]:
        F, J = body_forms(field)
        for (body, group), p in self.follower_pressures.items():
            if body != field.body.name:
                continue
            tags, _ = field.mesh.meshtags(self.gdim - 1, [group])
            ds = ufl.Measure("ds", domain=field.V.mesh, subdomain_data=tags)(1)
            G = ufl.Identity(self.gdim) + ufl.grad(field.u)
            # (axisymmetric: J = det F3 with the hoop stretch; in the meridian plane
            # F3^-T is G^-T)
            det = ufl.det(deformation_gradient(field.u, self.gdim, True)[1]) \
                if field.axisymmetric else ufl.det(G)
            N, v = ufl.FacetNormal(field.V.mesh), ufl.TestFunction(field.V)
            # Nanson: n da = J F^-T N dA; the pressure pushes into the body
            F += _thickness(field) * p * det * ufl.inner(ufl.inv(G).T * N, v) * ds
        return F, J

    def _inversion_guard(self, field: BodyField):
        """A check that no quadrature point of a finite-strain body has ``det F <= 0``."""
        _, F3 = deformation_gradient(field.u, self.gdim, field.axisymmetric)
        degree = 2 * (field.body.degree or compat.geometry_degree(field.V.mesh))
        expression = compat.quadrature_expression(ufl.det(F3), field.V.mesh, degree)

        def guard() -> str:
            J = compat.evaluate_on_owned_cells(expression, field.V.mesh)
            inverted = self.comm.allreduce(int((J <= 0.0).any() or not np.isfinite(J).all()))
            return f"an element of body {field.body.name!r} inverts (det F <= 0)" \
                if inverted else ""
        return guard

    @property
    def u(self) -> PETSc.Vec:
        """The displacement of every body and obstacle, in system numbering."""
        return self.system.x

    def rigid_body_modes(self) -> PETSc.NullSpace:
        """Translations and rotations of every body, orthonormal: the near null space
        that algebraic multigrid needs (see :meth:`BlockProblem.rigid_body_modes`)."""
        return self.system.rigid_body_modes()
