"""Node-to-surface contact as a piece of a FEniCSx script's own problem.

A :class:`NodeToSurface` couples the slave nodes of a facet set of one body with the
master faces of a facet set of another body, or with an analytic rigid obstacle
(:func:`rigid_plane`, :func:`rigid_sphere`, :func:`rigid_cylinder`).  It reads the
user's displacement vector and adds the contact forces and their exact tangent into the
user's PETSc residual and Jacobian, in the numbering of the user's system:

* one vector space ``V``: dolfinx's own numbering of ``V`` (``u.vector``);
* several spaces ``[V_0, V_1, ...]`` (``spaces=``): the blocks joined as dolfinx's block
  assemblers join them (on each rank, the owned dofs of ``V_0``, then of ``V_1``, ...).

One increment of a load-stepping loop::

    contact.begin(x)                    # first iterate: search candidates, checkpoint
    A = create_matrix(a, [contact])     # sparsity of the form plus the contact couplings
    for each Newton iterate x:
        contact.update(x)               # pair slave nodes with faces, evaluate elements
        ...assemble the bodies' residual into b...;  contact.add_residual(b, bcs)
        ...assemble their Jacobian into A...;        contact.add_jacobian(A, bcs)
    contact.commit()                    # or contact.rollback() before a smaller increment

The slave areas and the slip origin are those of the converged state the increment starts
from (the last commit's iterate, see :meth:`NodeToSurface.begin`), whatever the first iterate.

Dirichlet rows are left as dolfinx makes them: the contact adds nothing to the rows and
columns of the dofs of ``bcs``.  Units are the user's (force, length); a penalty ``K``
is a pressure per length.
"""
from __future__ import annotations

import uuid
from dataclasses import asdict, dataclass, replace
from typing import Optional, Sequence, Union

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from dolfinx_friction import _compat as compat
from dolfinx_friction import rules
from dolfinx_friction.contact.element import OPEN, ContactParameters
from dolfinx_friction.contact.laws import Exponential, Law, Linear, Tabular
from dolfinx_friction.errors import ContactSetupError
from dolfinx_friction.fem.axisymmetric import section_fault
from dolfinx_friction.fem.contact_assembly import ContactAssembly
from dolfinx_friction.contact.slave_weights import is_quadratic
from dolfinx_friction.fem.contact_settings import CALCULIX, ContactSettings, default_distribution
from dolfinx_friction.fem.faceting import mid_side_depths
from dolfinx_friction.fem.mortar_distribution import MortarDistribution
from dolfinx_friction.fem.numbering import BodyField, DofLayout
from dolfinx_friction.fem.obstacles import (  # noqa: F401  (rigid_*: re-exported)
    Obstacle, SignedDistance, _vector, rigid_cylinder, rigid_plane, rigid_sdf, rigid_sphere,
    rotation_size)
from dolfinx_friction.fem.pairing import ContactInteraction, Exchange, RigidMaster
from dolfinx_friction.fem.surfaces import SlaveNodes, face_type_of, master_faces
from dolfinx_friction.fem.tagged_mesh import BodyMesh
from dolfinx_friction.rules import SceneError, modulus

NO_ELEMENT = -1  #: status of a slave node without a contact element (far from the master)
#: the attribute of a PETSc matrix that records which pairs' couplings its pattern holds
_MATRIX_ATTR = "dolfinx_friction_couplings"


def make_law(pair) -> Law:
    """The pressure-overclosure law of contact settings, defaults resolved
    (:class:`~dolfinx_friction.fem.contact_settings.ContactSettings`, a scene
    ``ContactPair``)."""
    if pair.law == "exponential":
        return Exponential(pair.c0, pair.p0)
    if pair.law == "tabular":
        p, d = zip(*pair.table)
        return Tabular(tuple(p), tuple(d))
    return Linear(pair.K, pair.sigma_inf, pair.c0)


@dataclass(frozen=True)
class Surface:
    """Facets of one body: those of ``tags`` (facet MeshTags of ``V.mesh`` itself: tags of
    another mesh are refused) equal to ``value``, on the vector Lagrange space ``V`` of the
    body's displacement."""

    V: object
    tags: object
    value: int

    @property
    def label(self) -> str:
        return f"facets tagged {self.value}"


@dataclass
class ContactState:
    """The contact at the slave nodes this rank owns, arrays of length ``n``.

    ``status``: :data:`NO_ELEMENT` (-1), 0 open, 1 stick, 2 slip.  ``normal_force``
    [force] > 0 in compression (slightly negative for an open element within the linear
    law's tension range), ``pressure`` = ``normal_force / area`` [force / area];
    ``tangential_force`` (n, gdim) [force] is the friction force of the slave node on the
    master, ``traction`` = ``-tangential_force / area`` the tangential traction acting on
    the slave body; ``force`` (n, gdim) [force] the whole contact force on the slave node;
    ``gap`` [length] the clearance (< 0: overclosure); ``slip`` [length] the accumulated
    slip; ``area`` the node's representative area (deformed, at the increment's start);
    ``reference_area`` on the undeformed faces and ``reference_pressure`` =
    ``normal_force / reference_area`` (the nominal pressure, as small-strain closed forms
    give it).  Nodes without an element have zeros.
    """

    nodes: np.ndarray  # (n,) local node (dof block) index in the slave space
    X: np.ndarray  # (n, gdim) reference coordinates
    x: np.ndarray  # (n, gdim) current coordinates
    status: np.ndarray
    gap: np.ndarray
    normal_force: np.ndarray
    pressure: np.ndarray
    tangential_force: np.ndarray
    traction: np.ndarray
    slip: np.ndarray
    force: np.ndarray
    area: np.ndarray
    reference_area: np.ndarray
    reference_pressure: np.ndarray

    @property
    def has_element(self) -> np.ndarray:
        """The nodes paired with a master (open or closed), (n,) bool."""
        return self.status != NO_ELEMENT


@dataclass
class Support:
    """Where a contact pair holds its slave body against its master: this rank's closed
    slave nodes (stick or slip) at the last :meth:`NodeToSurface.update`.  A frictionless
    pair resists the relative motion of slave and master along the normal there, a
    frictional one in every direction."""

    slave: int  # block of the slave body in the pair's spaces
    master: Optional[int]  # block of the master body; None for a rigid obstacle
    obstacle: Optional[int]  # index of a rigid obstacle whose translation is an unknown
    frictional: bool
    x: np.ndarray  # (n, gdim) current coordinates of the closed slave nodes [length]
    normal: np.ndarray  # (n, gdim) their unit contact normals


@dataclass
class NormalModel:
    """A frictionless pair's elements at their last evaluation as overclosures affine in
    the unknowns (normals and projections frozen) under a bilinear law: element ``i``
    carries ``F_N = k_i max(d_i + a_i . du, 0) - s_i`` on its ``dofs`` (where the
    overclosure is at least ``width_i`` from 0: the law's regularisation lies within).
    What a Newton step can solve exactly for the contact statuses
    (:meth:`NodeToSurface.normal_model`)."""

    dofs: np.ndarray  # (n, m) global dofs of each element's nodes (-1: none)
    a: np.ndarray  # (n, m) gradient of the overclosure on them [-]
    d: np.ndarray  # (n,) overclosure the law sees [length]
    force: np.ndarray  # (n,) normal force F_N at d (> 0 in compression) [force]
    k: np.ndarray  # (n,) stiffness of the closed law [force / length]
    s: np.ndarray  # (n,) tension of the open law within the cutoff [force]
    width: np.ndarray  # (n,) the law is this bilinear one where |d| >= width [length]
    closed: np.ndarray  # (n,) bool: the element's status is not open


def _check_space(V, role: str) -> int:
    gdim = V.mesh.geometry.dim
    if V.dofmap.index_map_bs != gdim:
        raise ContactSetupError(f"{role}: the function space has {V.dofmap.index_map_bs} "
                                f"component(s), contact needs a vector space of the mesh's "
                                f"dimension {gdim}")
    return gdim


def _facets(surface: Surface, role: str, comm: MPI.Comm) -> np.ndarray:
    mesh = surface.V.mesh
    if surface.tags.dim != mesh.topology.dim - 1:
        raise ContactSetupError(f"{role}: the tags have dimension {surface.tags.dim}, facets "
                                f"of this mesh have {mesh.topology.dim - 1}")
    if not compat.tags_of(surface.tags, mesh):
        raise ContactSetupError(f"{role}: the tags of {surface.label} were made on another "
                                f"mesh than the function space's: give the tags of V.mesh")
    facets = compat.tagged(surface.tags, surface.value)
    # each facet on one rank only: its owner (a ghost facet would count twice in the
    # slave areas and appear twice as a master face)
    facets = facets[facets < mesh.topology.index_map(mesh.topology.dim - 1).size_local]
    if not comm.allreduce(len(facets)):
        present = sorted(set().union(*comm.allgather(set(np.unique(surface.tags.values)
                                                          .tolist()))))
        raise ContactSetupError(f"{role}: no facet is tagged {surface.value} (the tags hold "
                                f"{present})")
    return facets


class NodeToSurface:
    """Penalty node-to-surface contact with Coulomb friction between two surfaces.

    Parameters
    ----------
    slave : Surface
        The facets whose nodes are projected onto the master.
    master : Surface or Obstacle
        Master facets of a (usually other) body, an analytic rigid obstacle, or one given by
        a signed distance (:func:`rigid_sdf`); a rigid obstacle's translation is
        :attr:`obstacle_translation` (prescribed, no dofs), its rotation
        :attr:`obstacle_rotation`.
    spaces : sequence of dolfinx FunctionSpaces, optional
        The spaces of the user's system, in block order (default: the slave's space,
        then the master's if it is another one).
    law : Law, optional
        Pressure-overclosure law (``contact.Linear``, ``Exponential``, ``Tabular``);
        default: the linear law with penalty ``K``, ``sigma_inf``, ``c0``.
    K, sigma_inf, c0 : float or str, optional
        The linear law's penalty [pressure/length], tension limit [pressure] and cutoff
        factor; defaults 10 E/h (h: :attr:`spacing`), E / 70000, 1e-3 (docs/theory.md
        §8); ``K="calculix"``: CalculiX's 50 E.
    mu : float
        Coulomb friction coefficient (0: frictionless, the friction path is skipped).
    stick_slope : float or str, optional
        Tangential penalty ``lambda`` [pressure/length], default E/h; ``"calculix"``: E / 2.
    E : float, optional
        The slave body's Young's modulus, for the defaults above.
    tangent : str
        ``"consistent"`` (the exact tangent) or ``"calculix"``.
    thickness : float
        Out-of-plane thickness of a 2D (plane) body, scales slave areas.
    axisymmetric : bool
        The 2D meshes are meridian sections (r = x >= 0; :mod:`~dolfinx_friction.fem.
        axisymmetric`): slave areas are those of the revolved faces, the contact forces
        are per full revolution (``thickness`` is not used).
    pairing_iterations : int
        Newton iterations per increment that re-pair slave nodes (CalculiX: 8; 1 is small
        sliding).
    method : str
        ``"penalty"`` (default) or ``"augmented"``: augmented Lagrangian, multipliers
        updated by :meth:`augment` (Uzawa) until the overclosure and the elastic slip of
        sticking nodes are below ``augmented_tolerance`` (default 1e-4) times the slave
        node spacing, K and lambda unchanged (docs/theory.md §6.5).
    distribution : str
        How a slave node's force reaches a deformable master's nodes: ``"nodal"`` with the
        master face's shape functions at the node's projection, ``"mortar"`` with
        mortar weights over the slave faces around the node, measured at the start of each
        increment (docs/theory.md §2.4: the contact patch test on non-matching meshes;
        quadratic slave faces then spread their nodes' forces over the faces as on a rigid
        obstacle, §2.1; nothing changes against a rigid obstacle).  Default (None):
        ``"mortar"`` for quadratic slave faces on a deformable master (not axisymmetric),
        ``"nodal"`` otherwise (:func:`~dolfinx_friction.fem.contact_settings.
        default_distribution`).
    obstacle_index, n_obstacles : int
        For a rigid obstacle whose translation is an unknown of a
        :class:`~dolfinx_friction.BlockProblem` with ``obstacles=n_obstacles`` (force- or
        displacement-driven): which one it is.  Default: a prescribed translation.

    Attributes
    ----------
    spacing : float
        The slave surface's node spacing ``h`` [length] the defaults are scaled with: the
        median over all slave nodes (all ranks) of each node's spacing in the reference
        configuration (its representative area per thickness in 2D, the square root of it
        in 3D; :class:`~dolfinx_friction.fem.surfaces.SlaveNodes`), to 12 significant digits
        (the same on any number of ranks).
    law, stick_slope, mu
        The contact law as used, defaults resolved (:meth:`resolved`).
    ramp : float
        Share of the initial overclosures (found at the first pairing) still removed from
        the clearances (docs/theory.md §3.4): ``1 - t`` in a first static step that
        resolves them gradually, 0 otherwise (default).
    """

    def __init__(self, slave: Surface, master: Union[Surface, Obstacle], *,
                 spaces: Optional[Sequence] = None, law: Optional[Law] = None,
                 K: Union[float, str, None] = None, sigma_inf: Optional[float] = None,
                 c0: Optional[float] = None, mu: float = 0.0,
                 stick_slope: Union[float, str, None] = None, E: Optional[float] = None,
                 tangent: str = "consistent", thickness: float = 1.0,
                 axisymmetric: bool = False,
                 pairing_iterations: int = 8, method: str = "penalty",
                 augmented_tolerance: float = 1e-4, distribution: Optional[str] = None,
                 name: str = "contact",
                 obstacle_index: Optional[int] = None, n_obstacles: int = 0,
                 body_names: tuple[str, str] = ("slave", "master")):
        comm = slave.V.mesh.comm
        self.comm, self.name = comm, name
        self.gdim = _check_space(slave.V, f"{name}: slave")
        if (not isinstance(master, (Surface, Obstacle, SignedDistance))
                and hasattr(master, "shape")):
            master = Obstacle.like(master)  # a scene's Rigid
        rigid = isinstance(master, (Obstacle, SignedDistance))
        if not rigid:
            if _check_space(master.V, f"{name}: master") != self.gdim:
                raise ContactSetupError(f"{name}: slave and master meshes differ in dimension")
        if spaces is None:
            spaces = [slave.V] if rigid or master.V is slave.V else [slave.V, master.V]
        self.spaces = list(spaces)
        given = self._given(law, K, sigma_inf, c0, mu, stick_slope, E, tangent,
                            pairing_iterations, method, augmented_tolerance, distribution)
        self.layout = DofLayout(comm, [V.dofmap.index_map for V in self.spaces], n_obstacles)
        slave_facets = _facets(slave, f"{name}: slave", comm)
        self._fields: list[BodyField] = []
        self._body_names = body_names
        slave_field = self._field(slave.V, "slave", slave_facets, thickness, axisymmetric)
        if rigid:
            if master.shape == "cylinder" and self.gdim != 3:
                raise ContactSetupError(f"{name}: a rigid cylinder needs a 3D mesh (use "
                                        f"rigid_sphere for a circle in 2D)")
            for key in ("point", "normal", "center", "axis", "reference"):
                v = getattr(master, key, None)
                if v is not None and len(v) != self.gdim:
                    raise ContactSetupError(f"{name}: the obstacle's {key} has {len(v)} "
                                            f"components, the mesh is {self.gdim}D")
            self._master_field = None
            self._obstacle = obstacle_index
            node = None
            if obstacle_index is not None:
                if not 0 <= obstacle_index < n_obstacles:
                    raise ContactSetupError(f"{name}: obstacle_index {obstacle_index} is not "
                                            f"one of the {n_obstacles} obstacles")
                node = self.layout.rigid_node(obstacle_index)
            master_side = RigidMaster(master, node, np.zeros(self.gdim))
        else:
            master_facets = _facets(master, f"{name}: master", comm)
            if master.V.mesh is slave.V.mesh:
                shared = np.intersect1d(master_facets, slave_facets)
                if comm.allreduce(len(shared)):
                    raise ContactSetupError(f"{name}: slave and master share facets: a "
                                            f"surface cannot contact itself")
            self._obstacle = None
            self._master_field = self._field(master.V, "master", master_facets, thickness,
                                             axisymmetric)
            # each facet once over all ranks: the ones this rank owns
            master_side = master_faces(self._master_field, "master")
        # quadratic slave faces spread their nodes' forces on rigid obstacles, and with the
        # mortar distribution (§2.1, §2.4)
        if given.distribution is None:
            given = replace(given, distribution=default_distribution(
                is_quadratic(face_type_of(slave_field)), rigid, axisymmetric))
        by_mortar = given.distribution == "mortar" and not rigid
        slaves = SlaveNodes(slave_field, "slave", subfaces=rigid or by_mortar)
        self._slave_field = slave_field
        #: (n,) how deep the mid-side nodes lie inside a curved surface of first-order
        #: geometry [length]; None on other meshes and faces (§2.1)
        self._chord_depth = mid_side_depths(slave_field, slaves.face, slaves.facet_nodes,
                                            slaves.local)
        # a node's area sums its faces' shares in an order that depends on the partition:
        # 12 digits make h, and the defaults scaled with it, the same on any number of ranks
        self.spacing = float(f"{np.median(np.concatenate(comm.allgather(slaves.spacing))):.12g}")
        self.params = self._parameters(given, law, E)
        mortar = (MortarDistribution(slave_field, slaves.face, slaves.facet_nodes, slaves.nodes,
                                     master_side) if by_mortar else None)
        self._interaction = ContactInteraction(comm, name, self.params.element, slaves,
                                               master_side, self.gdim,
                                               self.params.pairing_iterations, mortar)
        self.ramp = 0.0
        self._u_n: Optional[PETSc.Vec] = None
        self._saved: Optional[tuple] = None
        self._iteration = 0
        self._u_slaves = np.zeros((len(slaves.nodes), self.gdim))
        self._assembly = ContactAssembly(self._interaction, self.spaces, self.layout, name)
        #: changes whenever the candidate couplings (the matrix pattern) change
        self.couplings_version = 0
        #: counts the evaluations of the elements (an update that pairs the same elements
        #: at the iterate last evaluated keeps that evaluation)
        self.evaluations = 0
        self._evaluated_at: Optional[tuple] = None  # (x's local values, ramp) of the last
        self._key = uuid.uuid4().hex  # names this pair in the matrices' attributes

    @property
    def obstacle_translation(self) -> np.ndarray:
        """(gdim,) prescribed translation of the rigid obstacle [length]; set it (e.g. in
        the load function of an increment) before :meth:`begin`."""
        master = self._interaction.master
        if not isinstance(master, RigidMaster):
            raise AttributeError(f"{self.name}: the master is not a rigid obstacle")
        return master.translation.copy()

    @obstacle_translation.setter
    def obstacle_translation(self, value: Sequence[float]) -> None:
        master = self._interaction.master
        if not isinstance(master, RigidMaster):
            raise AttributeError(f"{self.name}: the master is not a rigid obstacle")
        master.translation[:] = _vector(value, f"{self.name}: obstacle translation")

    @property
    def obstacle_rotation(self) -> np.ndarray:
        """Prescribed rotation of the rigid obstacle about its reference point (its
        ``reference``, default its ``point`` or ``center``) [rad]: (1,) an angle in 2D
        (counter-clockwise), (3,) a rotation vector in 3D; set it (a number in 2D) before
        :meth:`begin`, like :attr:`obstacle_translation`.  The obstacle's current geometry
        is its reference shape rotated about the reference point, then translated."""
        return self._rigid_master().rotation.copy()

    @obstacle_rotation.setter
    def obstacle_rotation(self, value) -> None:
        master = self._rigid_master()
        size = rotation_size(self.gdim)
        theta = np.atleast_1d(np.asarray(value, dtype=float))
        if theta.shape != (size,):
            what = "an angle (a number)" if size == 1 else "a rotation vector of 3 numbers"
            raise ContactSetupError(f"{self.name}: obstacle rotation must be {what} in "
                                    f"{self.gdim}D, got {np.asarray(value).tolist()}")
        theta = _vector(theta, f"{self.name}: obstacle rotation")
        if master.rigid.pivot is None and any(theta):
            raise ContactSetupError(f"{self.name}: obstacle rotation: the obstacle "
                                    f"{master.rigid.name!r} has no reference point to rotate "
                                    f"about (give it a reference)")
        master.rotation[:] = theta

    def obstacle_moment(self):
        """Moment of the contact about the rigid obstacle's current reference point (its
        reference point translated), summed over all ranks (collective) [force * length]:
        ``sum (q - c - t) x f`` over the slave nodes' elements, ``q`` the obstacle's point
        under the node and ``f`` the element's force at the obstacle, which sums to
        :meth:`force` (the force that holds the obstacle against the body).  2D: a number
        (counter-clockwise positive); 3D: (3,)."""
        master = self._rigid_master()
        el, d = self._interaction.elements, self.gdim
        arm, f = np.zeros((0, d)), np.zeros((0, d))
        if el.result is not None and len(el.slave):
            x = self._interaction.slaves.X[el.slave] + self._u_slaves[el.slave]
            q = x - el.result.g_N[:, None] * el.normal
            pivot = master.rigid.pivot
            c = (np.zeros(d) if pivot is None else np.asarray(pivot, float)) \
                + self._interaction.master_motion
            arm, f = q - c, el.result.f[:, 0, :]
        if d == 2:
            return float(self.comm.allreduce(np.sum(arm[:, 0] * f[:, 1] - arm[:, 1] * f[:, 0])))
        return self.comm.allreduce(np.cross(arm, f).sum(axis=0))

    def _rigid_master(self) -> RigidMaster:
        master = self._interaction.master
        if not isinstance(master, RigidMaster):
            raise AttributeError(f"{self.name}: the master is not a rigid obstacle")
        return master

    @property
    def law(self) -> Law:
        """The pressure-overclosure law in use, defaults resolved (``Linear``: ``K``,
        ``sigma_inf``, ``c0``)."""
        return self.params.element.law

    @property
    def stick_slope(self) -> float:
        """The stick slope ``lambda`` in use [pressure/length], default resolved."""
        return self.params.element.stick_slope

    @property
    def mu(self) -> float:
        return self.params.element.mu

    @property
    def symmetric(self) -> bool:
        """Whether the contact tangent is symmetric: frictionless, with each slave node's
        force on the node itself (not spread over quadratic slave faces on an obstacle) and
        on the master face's nodes (not by mortar weights)."""
        inter = self._interaction
        return self.mu == 0.0 and inter.slaves.distribution is None and inter.mortar is None

    def resolved(self) -> dict:
        """The contact settings as used, every default resolved, as plain numbers: ``law``
        (``"linear"``, ``"exponential"``, ``"tabular"``) and its parameters (``K``,
        ``sigma_inf``, ``c0`` / ``c0``, ``p0`` / ``pressures``, ``overclosures``),
        ``mu``, ``stick_slope``, ``tangent``, ``pairing_iterations``, ``method``,
        ``augmented_tolerance``, ``distribution`` and the slave node ``spacing`` h the
        defaults scale with."""
        return {"law": type(self.law).__name__.lower(), **asdict(self.law), "mu": self.mu,
                "stick_slope": self.stick_slope, "tangent": self.params.element.tangent,
                "pairing_iterations": self.params.pairing_iterations,
                "method": self.params.method,
                "augmented_tolerance": self.params.augmented_tolerance,
                "distribution": self.params.distribution, "spacing": self.spacing}

    # ------------------------------------------------------------- set-up
    def _given(self, law, K, sigma_inf, c0, mu, stick_slope, E, tangent,
               pairing_iterations, method, augmented_tolerance,
               distribution) -> ContactSettings:
        """The parameters as given, checked by the contact settings' rules (the same
        one-line messages as a scene file's ``[[contact]]``); defaults still to be
        resolved."""
        try:
            given = ContactSettings(K=K, sigma_inf=sigma_inf, c0=c0, mu=mu,
                                    stick_slope=stick_slope, tangent=tangent,
                                    pairing_iterations=pairing_iterations, method=method,
                                    augmented_tolerance=augmented_tolerance,
                                    distribution=distribution)
            if E is not None:
                modulus(E, "E")
        except SceneError as error:
            raise ContactSetupError(f"{self.name}: {error.detail}") from None
        defaulted = [key for key, value in (("K", K if law is None else 1.0),
                                            ("sigma_inf", sigma_inf if law is None else 1.0),
                                            ("stick_slope", stick_slope if given.mu > 0 else 1.0))
                     if value is None or value == CALCULIX]
        if defaulted and E is None:
            raise ContactSetupError(f"{self.name}: give E (the slave body's Young's modulus) for "
                                    f"the default {', '.join(defaulted)}, or give them")
        return given

    def _parameters(self, given: ContactSettings, law: Optional[Law],
                    E: Optional[float]) -> "_Parameters":
        """Resolve the defaults with the slave node spacing (:meth:`ContactSettings.resolved`)."""
        pair = given.resolved(E or 1.0, self.spacing)
        for key in ("K", "stick_slope"):
            value = getattr(pair, key)
            if not 0.0 < value < np.inf:
                raise ContactSetupError(f"{self.name}: the default {key} = {value:g} (from E = "
                                        f"{E} and the slave node spacing h = "
                                        f"{self.spacing:g}) is not a positive finite number: "
                                        f"give {key}")
        law = law if law is not None else make_law(pair)
        return _Parameters(ContactParameters(law, pair.mu, pair.stick_slope, pair.tangent),
                           pair.pairing_iterations, pair.method, pair.augmented_tolerance,
                           pair.distribution)

    def _field(self, V, group: str, facets: np.ndarray, thickness: float,
               axisymmetric: bool) -> BodyField:
        block = next((b for b, W in enumerate(self.spaces) if W is V), None)
        if block is None:
            raise ContactSetupError(f"{self.name}: the {group}'s function space is not one "
                                    f"of `spaces`")
        existing = next((f for f in self._fields if f.block == block), None)
        if existing is not None:
            existing.mesh.groups[group] = (V.mesh.topology.dim - 1, facets)
            return existing
        mesh = V.mesh
        name = self._body_names[0 if group == "slave" else 1]
        rules.name(name, "body.name")  # the scene's rules of a body's name and thickness
        thickness = rules.number(gt=0)(float(thickness), "body.thickness")
        groups = {group: (mesh.topology.dim - 1, facets)}
        X = V.tabulate_dof_coordinates()[:, : self.gdim].copy()
        f = BodyField(name, thickness, BodyMesh(name, mesh, groups), V, compat.function(V),
                      block, self.layout.nodes(block), X, axisymmetric=bool(axisymmetric))
        fault = section_fault(f) if f.axisymmetric else ""
        if fault:
            raise ContactSetupError(f"{self.name}: {group} (axisymmetric): {fault}")
        self._fields.append(f)
        return f

    # ------------------------------------------------------------- increments
    def begin(self, x: PETSc.Vec, start: Optional[PETSc.Vec] = None) -> None:
        """Start an increment (collective): checkpoint the friction history for
        :meth:`rollback` and search the candidate master faces of every slave node at
        ``x``, the increment's first iterate (a predictor, or the last converged state).

        What is measured at the start of the increment is measured at ``start``, the
        converged state the increment starts from, whatever ``x`` is: the slave areas
        ``A_p`` (and with them the contact forces' scale and the pairing cutoff), and the
        origin of the slip of nodes that touch anew.  Default: the iterate at which the
        last :meth:`commit` accepted an increment (before the first one: ``x``).  So the
        converged answer does not depend on the first iterate."""
        if self._u_n is None:
            self._u_n = x.duplicate()
            (x if start is None else start).copy(self._u_n)
        elif start is not None:
            start.copy(self._u_n)
        self._evaluated_at = None
        self._saved = self._interaction.save()
        self._load_fields(self._u_n)
        self._interaction.measure_areas()
        self._measure_mortar()
        self._search(x, True)
        self._iteration = 0

    def update(self, x: PETSc.Vec, pairing: bool = True, search: bool = True) -> bool:
        """Pair the slave nodes at the iterate ``x`` and evaluate the elements (collective).

        Pairing happens in the first ``pairing_iterations`` calls of an increment with
        ``pairing=True`` (pass ``False`` for line-search trials).  Returns True when a node
        slid past all its candidate faces, they were searched again (``search``) and the
        new couplings left the matrix's pattern: make the matrix again
        (:func:`create_matrix`).  Without ``search`` such a node keeps the face it misses
        least.
        """
        if self._u_n is None:
            raise RuntimeError(f"{self.name}: call begin(x) at the start of the increment")
        inter, searched, changed = self._interaction, False, False
        evaluated = inter.elements
        if pairing and self._iteration < inter.pairing_iterations:
            inter.pair(x, self._iteration)
            if (search and self._iteration > 0
                    and self.comm.allreduce(int(inter.needs_search()))):
                searched, changed = True, self._search(x, first=False)
                inter.pair(x, self._iteration)
            inter.mark_off_surface()
        if pairing:
            self._iteration += 1
        values = x.getArray(readonly=True)
        if not searched and self._same_evaluation(evaluated, values):
            inter.elements = evaluated  # paired as before at the same iterate: keep it
            return False
        inter.evaluate(x, self._u_n, self.ramp)
        self.evaluations += 1
        self._evaluated_at = (values.copy(), self.ramp)
        self._u_slaves = inter.slave_displacements(x)
        return changed

    def _same_evaluation(self, evaluated, values: np.ndarray) -> bool:
        """Whether the current elements are those of the last evaluation (the same
        candidates) at the same iterate and ramp, on every rank (collective)."""
        now, last = self._interaction.elements, self._evaluated_at
        same = (last is not None and evaluated is not None and evaluated.result is not None
                and last[1] == self.ramp and np.array_equal(now.candidate, evaluated.candidate)
                and np.array_equal(last[0], values))
        return self.comm.allreduce(int(not same)) == 0

    def commit(self) -> None:
        """Accept the increment at the iterate of the last :meth:`update`: its trial friction
        history and the iterate itself become the start state of the next increment."""
        if self._evaluated_at is not None:
            self._u_n.setArray(self._evaluated_at[0])
        self._evaluated_at = None
        self._interaction.commit()
        self._saved = None

    def augment(self) -> bool:
        """With ``method="augmented"``, after a converged solve of the increment: one Uzawa
        update of the multipliers where the overclosure or a sticking node's elastic slip
        exceeds ``augmented_tolerance`` times the slave node spacing on some node; returns
        whether it updated them (then solve the increment again: the contact forces are
        those of the next :meth:`update`).  False with the penalty method.  Collective."""
        if self.params.method != "augmented":
            return False
        inter = self._interaction
        violation = self.comm.allreduce(inter.violation(), op=MPI.MAX)
        if not violation > self.params.augmented_tolerance:
            return False
        inter.augment()
        self._evaluated_at = None
        return True

    def stale_pairing(self) -> int:
        """After a converged solve of the increment (collective): where the pairing froze
        (after ``pairing_iterations`` > 1) before the solve converged, how many slave nodes
        a pairing at the converged iterate closes or opens against the pairing the solve
        converged with; 0 otherwise.  Not 0: the increment converged to the equilibrium
        of stale pairings, not an answer (a node that only changes face is what the
        freeze is for: one chattering between two faces).  With one pairing per increment
        (small sliding) the pairing lags by an increment by design: 0."""
        pairings = self._interaction.pairing_iterations
        if pairings == 1 or self._iteration <= pairings or self._evaluated_at is None:
            return 0  # paired at the last iterate, or once by design
        x = self._u_n.duplicate()
        x.setArray(self._evaluated_at[0])
        changed = self._interaction.closed_change(x, self._u_n, self.ramp)
        x.destroy()
        return self.comm.allreduce(changed)

    def rollback(self) -> None:
        """Forget the increment: restore the history saved by :meth:`begin`."""
        self._evaluated_at = None
        if self._saved is not None:
            self._interaction.restore(self._saved)

    def _load_fields(self, x: PETSc.Vec) -> None:
        """Copy the bodies' displacements in ``x`` into their Functions (collective)."""
        for f in self._fields:
            f.u.x.array[: f.n_owned * self.gdim] = x.getArray(readonly=True)[
                self.layout.owned_slice(f.block, self.gdim)]
            compat.scatter_forward(f.u)

    def _measure_mortar(self) -> None:
        """The mortar weights on the bodies as loaded (:meth:`_load_fields`), if any."""
        mortar = self._interaction.mortar
        if mortar is None:
            return
        x = [f.X + f.u.x.array.reshape(-1, self.gdim)[: len(f.X)]
             for f in (self._slave_field, self._master_field)]
        mortar.update(x[0], x[1][self._interaction.master.local])

    def _search(self, x: PETSc.Vec, first: bool) -> bool:
        """Search the candidates at ``x``; a new matrix pattern (:attr:`couplings_version`)
        where the current one misses couplings of the candidates or of the mortar weights
        on some rank (collective).  Returns whether the pattern changed."""
        self._load_fields(x)
        master_u = None
        if self._master_field is not None:
            f = self._master_field
            master_u = f.u.x.array.reshape(-1, self.gdim)[self._interaction.master.local]
        self._interaction.search(x, master_u, first)
        if not self.comm.allreduce(0 if self._assembly.holds() else 1):
            return False
        self._assembly.renew()
        self.couplings_version += 1
        return True

    # ------------------------------------------------------------- assembly
    def surface_dofs(self) -> np.ndarray:
        """Sorted global dofs of every node this rank's part of the contact can couple: its
        slave nodes and its master faces' nodes (a rigid obstacle's translation excluded).
        In serial, the couplings of every search lie within them."""
        return self._assembly.surface_dofs()

    def add_residual(self, b: PETSc.Vec, bcs: Sequence = ()) -> None:
        """Add the contact forces (internal forces: residual = internal - external) into
        ``b`` (collective; ``b`` is assembled afterwards)."""
        self._assembly.add_residual(b, bcs)

    def add_jacobian(self, A: PETSc.Mat, bcs: Sequence = ()) -> None:
        """Add the contact tangent into ``A`` (collective; assembled afterwards).

        ``A`` must hold the candidate couplings in its pattern: make it with
        :func:`create_matrix` after :meth:`begin` (and again when :meth:`update`
        returned True).
        """
        if (A.getAttr(_MATRIX_ATTR) or {}).get(self._key) != self.couplings_version:
            raise ContactSetupError(f"{self.name}: the matrix has no slots for the current "
                                    f"contact couplings: make it with create_matrix(...) "
                                    f"after begin() (and again when update() returns True)")
        self._assembly.add_jacobian(A, bcs)

    def add_roundoff(self, s: PETSc.Vec) -> None:
        """Add the size of the round-off of the contact forces (their sensitivity to the
        coordinates, which carry the clearance) into ``s``, per dof (not assembled)."""
        self._assembly.add_roundoff(s)

    def couplings(self) -> tuple[np.ndarray, np.ndarray]:
        """Global ``(rows, cols)`` of every entry the contact tangent may fill until the
        next search (each candidate element's dofs, all against all), each once."""
        return self._assembly.couplings()

    def coupling_values(self, bcs: Sequence = ()) -> np.ndarray:
        """Tangent values in the order of :meth:`couplings`: the sum of the elements'
        entries (0 where no element couples, and in the rows and columns of ``bcs``)."""
        return self._assembly.coupling_values(bcs)

    def coupling_entries(self) -> tuple[np.ndarray, np.ndarray]:
        """The current elements' tangent values by their index among :meth:`couplings`:
        ``(index, values)``, ``index`` distinct (what :meth:`coupling_values` holds there
        without bcs; zero elsewhere): a few entries where a search found many candidates."""
        return self._assembly.coupling_entries()

    def element_entries(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Global ``(rows, cols, values)`` of the current elements' tangents only (what
        :meth:`coupling_values` holds where it is not zero by construction; a rigid
        obstacle's rows and columns left out; no bcs)."""
        return self._assembly.element_entries()

    def register_matrix(self, A: PETSc.Mat) -> None:
        """Declare that ``A``'s pattern holds the current couplings (done by
        :func:`create_matrix`; for a matrix preallocated some other way)."""
        marks = A.getAttr(_MATRIX_ATTR) or {}
        marks[self._key] = self.couplings_version
        A.setAttr(_MATRIX_ATTR, marks)

    # ------------------------------------------------------------- results
    def state(self) -> ContactState:
        """The contact at this rank's owned slave nodes (after :meth:`update`)."""
        inter = self._interaction
        slaves = inter.slaves
        n, d = len(slaves.nodes), self.gdim
        zero, zeros = np.zeros(n), np.zeros((n, d))
        out = ContactState(slaves.local.copy(), slaves.X.copy(), slaves.X + self._u_slaves,
                           np.full(n, NO_ELEMENT), zero.copy(), zero.copy(), zero.copy(),
                           zeros.copy(), zeros.copy(), zero.copy(), zeros.copy(),
                           slaves.area.copy(), slaves.reference_area.copy(), zero.copy())
        el = inter.elements
        r = el.result
        if r is not None:
            s, area = el.slave, slaves.area[el.slave]
            out.status[s] = r.status
            out.gap[s] = r.g_N
            out.normal_force[s] = r.F_N
            out.pressure[s] = r.F_N / area
            out.reference_pressure[s] = r.F_N / slaves.reference_area[el.slave]
            out.tangential_force[s] = r.F_T
            out.traction[s] = -r.F_T / area[:, None]
            out.force[s] = -r.f[:, -1, :]
            if r.trial is not None:
                out.slip[s] = np.linalg.norm(r.trial.g_p, axis=1)
        return out

    def coulomb_excess(self) -> float:
        """By how much the largest friction force of this rank's slave nodes exceeds mu
        times the magnitude of its normal force (a law's tension range holds by friction
        too), beyond round-off (1e-9 of the largest normal force): 0.0 where Coulomb's law
        holds [force]."""
        r = self._interaction.elements.result
        if r is None or not len(r.F_N):
            return 0.0
        excess = np.linalg.norm(r.F_T, axis=1) - self.mu * np.abs(r.F_N)
        return max(float(excess.max()) - 1e-9 * float(np.abs(r.F_N).max()), 0.0)

    def force(self) -> np.ndarray:
        """(gdim,) total contact force on the slave body, summed over all ranks
        (collective)."""
        return self.comm.allreduce(self.state().force.sum(axis=0))

    def pairing(self) -> np.ndarray:
        """(n, 2) status and global master face id of every owned slave node ((-1, -1)
        without an element; face -1 on a rigid obstacle): what the Newton trace compares."""
        return self._interaction.contact_state()

    def penetration(self) -> float:
        """Largest overclosure the law acts on, relative to the slave node spacing, over all
        ranks (collective): a penalty too soft for the mesh shows here."""
        return self.comm.allreduce(self._interaction.penetration(), op=MPI.MAX)

    def faceting(self) -> tuple[float, float]:
        """Quadratic slave faces on a mesh of first-order geometry: the largest chord depth
        ``h^2/8R`` of the closed slave nodes' mid-side nodes [length] and its ratio to the
        largest overclosure, over all ranks (collective); (0, 0) on other meshes or with
        nothing closed.  The vertex nodes carry about that ratio more pressure (§2.1)."""
        if self._chord_depth is None:
            return 0.0, 0.0
        depth, over = self._interaction.closed_depth(self._chord_depth)
        depth = self.comm.allreduce(depth, op=MPI.MAX)
        over = self.comm.allreduce(over, op=MPI.MAX)
        return depth, (depth / over if over > 0.0 else 0.0)

    def detached(self) -> int:
        """Slave nodes closed at the last commit that slid off the master surface in this
        increment, over all ranks (collective)."""
        return int(self.comm.allreduce(self._interaction.detached()))

    def zone_vanished(self) -> bool:
        """Whether all of a contact zone closed at the last commit is gone, with some of its
        nodes off the master surface (collective): more often a diverging iterate that
        threw the zone away than a real slide off the end."""
        inter = self._interaction
        before, now, off = self.comm.allreduce(
            np.array([inter.closed.sum(), inter.counts()[0], inter.detached()]))
        return bool(before > 0 and now == 0 and off > 0)

    def support(self) -> Support:
        """Where the pair holds its bodies against each other now (this rank's closed slave
        nodes; none before the first :meth:`update`)."""
        el = self._interaction.elements
        if el.result is None:
            s, normal = np.zeros(0, np.int64), np.zeros((0, self.gdim))
        else:
            closed = el.result.status != OPEN
            s, normal = el.slave[closed], el.normal[closed]
        master = self._master_field
        return Support(self._slave_field.block, None if master is None else master.block,
                       self._obstacle, self.mu > 0.0,
                       self._interaction.slaves.X[s] + self._u_slaves[s], normal)

    def normal_model(self) -> Optional[NormalModel]:
        """This rank's elements at their last :meth:`update` as a :class:`NormalModel`;
        None where the pair has friction, a law that is not bilinear
        (:meth:`~dolfinx_friction.contact.laws.Law.bilinear`), or spreads its slave forces
        (mortar weights, quadratic slave faces on an obstacle).  Not collective."""
        model = self._interaction.normal_model() if not self._assembly.spreads() else None
        if model is None:
            return None
        a, d, k, s, width, closed = model
        el = self._interaction.elements
        dofs = self._assembly.node_dofs(el.nodes)
        return NormalModel(dofs, a.reshape(dofs.shape), d, el.result.F_N, k, s,
                           np.full(len(d), width), closed)

    def exchange(self) -> Exchange:
        """What this rank sent and received for the pair's searches so far
        (:class:`~dolfinx_friction.fem.pairing.Exchange`; a copy, not collective)."""
        return replace(self._interaction.exchange)

    def counts(self) -> tuple[int, int]:
        """Slave nodes in contact (closed) and slipping, over all ranks (collective)."""
        return tuple(int(c) for c in self.comm.allreduce(np.asarray(self._interaction.counts())))

    def fields(self) -> dict:
        """The state as dolfinx Functions on the slave body's mesh, for dolfinx's writers:
        :func:`~dolfinx_friction.fem.contact_fields.nodal_fields`'s ``contact_pressure``,
        ``slip`` and ``status`` (scalar) and ``tangential_traction`` (vector), with its
        names and status codes (0, status -1 away from the slave nodes)."""
        from dolfinx_friction.fem.contact_fields import nodal_fields
        V = self._slave_field.V
        S = compat.scalar_space(V.mesh, compat.space_degree(V))
        n_nodes = len(compat.function(S).x.array)
        out = {}
        for key, values in nodal_fields([self.state()], n_nodes, self.gdim).items():
            g = compat.function(V if values.shape[1] > 1 else S)
            g.x.array[:] = values.ravel()
            compat.scatter_forward(g)
            g.name = key
            out[key] = g
        return out


@dataclass(frozen=True)
class _Parameters:
    element: ContactParameters
    pairing_iterations: int
    method: str
    augmented_tolerance: float
    distribution: str


def create_matrix(a, contacts: Sequence[NodeToSurface] = ()) -> PETSc.Mat:
    """A PETSc matrix for the compiled bilinear form ``a`` (one space; on dolfinx 0.10+ also
    a 2-D list of them, in dolfinx's block numbering) whose sparsity also holds the current
    couplings of ``contacts``: dolfinx assembles ``a`` into it as into its own matrix, and
    the contacts add their tangents without new non-zeros.
    Collective; call after :meth:`NodeToSurface.begin`."""
    from dolfinx_friction.fem.pattern import CooPattern
    base = compat.create_matrix(a)
    compat.assemble_matrix_into(base, a)
    indptr, cols, _ = base.getValuesCSR()
    start, end = base.getOwnershipRange()
    rows = np.repeat(np.arange(start, end, dtype=np.int64), np.diff(indptr))
    blocks = [(rows, cols)] + [c.couplings() for c in contacts]
    pattern = CooPattern(base.getComm().tompi4py(), end - start, blocks)
    A = pattern.create_matrix(base.getBlockSize())
    A.setLGMap(*base.getLGMap())
    base.destroy()
    for c in contacts:
        c.register_matrix(A)
    return A
