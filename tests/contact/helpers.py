"""Shared test helpers for the contact element (pure numpy, no dolfinx).

* seeded, well-conditioned random master faces of every type (2D segments,
  3D faces), warped/curved where the type allows it, with random rigid
  placements (rotation + translation) and small master displacements;
* slave nodes placed at a prescribed clearance above a prescribed interior
  point of the *current* face, so the exact projection is known;
* friction histories built so that the trial force is a prescribed multiple
  of the Coulomb limit (well inside stick, or well inside slip);
* rigid obstacles (plane, sphere, circle in 2D, cylinder);
* a central-difference Jacobian of ``evaluate(...).f`` with respect to all
  element dofs, history frozen, vectorised over pairs (the loop runs only over
  the ``nodes * d`` perturbation directions);
* a small registry of the worst measured values, printed at the end of the
  session by ``conftest.py``.

Length scale: faces have a size of about ``L = 1``; penetrations are
``1e-4 .. 3e-2``; the finite-difference step is ``H = 1e-7 * L``
(docs/theory.md §11).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable, Optional

import numpy as np

from dolfinx_friction.contact.element import (
    ContactParameters,
    ElementResult,
    Kinematics,
    evaluate,
    face_kinematics,
    rigid_kinematics,
)
from dolfinx_friction.contact.friction import FrictionState
from dolfinx_friction.contact.laws import Exponential, Law, Linear, Tabular
from dolfinx_friction.contact.shapes import FACE_TYPES, FaceType, surface_vector

FACES_2D = ("L2", "L3")
FACES_3D = ("T3", "T6", "Q4", "Q9")
FACES = FACES_2D + FACES_3D
GDIM = {name: 2 if name in FACES_2D else 3 for name in FACES}
LAW_NAMES = ("linear", "exponential", "tabular")
STATES = ("open", "frictionless", "stick", "slip")

H = 1e-7  # finite-difference step (length scale 1)
MU = 0.3
STICK_SLOPE = 100.0  # lambda [F/L^3]; K_t = lambda A_p

LAWS: dict[str, Law] = {
    # eps = pi sigma_inf / K ~ 9.4e-4: smooth on the scale of the penetrations used
    "linear": Linear(K=1e4, sigma_inf=3.0),
    # beta = ln(100)/0.05 ~ 92; the e^23 cap is far away (d ~ 0.24 for A p0 ~ 2.5)
    "exponential": Exponential(c0=0.05, p0=10.0),
    # first point at a negative overclosure, so small clearances still carry pressure
    "tabular": Tabular(pressures=(0.0, 5.0, 40.0, 200.0, 800.0),
                       overclosures=(-0.002, 0.0, 0.006, 0.016, 0.03)),
}

# --------------------------------------------------------------------------- worst values
WORST: dict[str, float] = {}


def record(key: str, value: float, smallest: bool = False) -> float:
    """Keep the worst value measured under ``key`` (printed at session end): the largest,
    or with ``smallest`` the smallest (for quantities that must stay large)."""
    value = float(value)
    if smallest:
        WORST[key] = min(WORST.get(key, np.inf), value)
    else:
        WORST[key] = max(WORST.get(key, 0.0), value)
    return value


# --------------------------------------------------------------------------- geometry
def rng_for(*keys) -> np.random.Generator:
    """A generator seeded from arbitrary hashable keys (stable across runs)."""
    text = "|".join(str(k) for k in keys)
    return np.random.default_rng([ord(c) for c in text] or [0])


def random_rotation(rng: np.random.Generator, d: int) -> np.ndarray:
    Q, R = np.linalg.qr(rng.standard_normal((d, d)))
    Q = Q * np.sign(np.diag(R))
    if np.linalg.det(Q) < 0:
        Q[:, 0] = -Q[:, 0]
    return Q


def planar_layout(face: FaceType) -> np.ndarray:
    """Node coordinates in the face's own plane, size ~ 1, centroid at 0."""
    if face.simplex:
        return face.nodes - 1.0 / 3.0
    return 0.5 * face.nodes


def random_faces(face: FaceType, n: int, rng: np.random.Generator, *, warp: float = 0.15,
                 jitter: float = 0.06, scale: float = 1.0, offset: float = 0.5) -> np.ndarray:
    """Current node coordinates (n, nn, d) of ``n`` random, well-conditioned faces.

    Reference layout + a random quadratic out-of-plane warp (curves quadratic
    faces, bends warped Q4) + nodal jitter of ``jitter`` (also out of plane,
    which warps Q4) + a random rotation and translation.
    """
    lay = planar_layout(face)
    nn = face.n_nodes
    out = []
    for _ in range(n):
        if face.fdim == 1:
            x = lay[:, 0]
            y = warp * rng.uniform(-1, 1) * 4 * x * x
            local = np.stack([x, y], axis=-1)
        else:
            x, y = lay[:, 0], lay[:, 1]
            a, b, c = rng.uniform(-1, 1, 3)
            z = warp * (a * x * x + b * x * y + c * y * y) * 2
            local = np.stack([x, y, z], axis=-1)
        local = local + jitter * rng.uniform(-1, 1, local.shape)
        Q = random_rotation(rng, local.shape[1])
        out.append(scale * (local @ Q.T + offset * rng.uniform(-1, 1, local.shape[1])))
    X = np.array(out)
    assert X.shape == (n, nn, GDIM[face.name])
    return X


def flat_faces(face: FaceType, n: int, rng: np.random.Generator, *, affine: bool = True,
               in_plane_jitter: float = 0.0) -> np.ndarray:
    """Flat faces (n, nn, d): an affine image of the reference element (straight edges) or,
    with ``affine=False``, a general planar one (corner jitter; edge nodes at edge midpoints
    unless ``in_plane_jitter`` > 0)."""
    lay = planar_layout(face)
    out = []
    for _ in range(n):
        A = np.eye(face.fdim) + 0.3 * rng.uniform(-1, 1, (face.fdim, face.fdim))
        local = lay @ A.T
        if not affine:
            local = local + 0.1 * rng.uniform(-1, 1, local.shape)
            # keep edge/interior nodes where the bilinear/linear map of the corners puts them
            nv = 2 if face.fdim == 1 else (3 if face.simplex else 4)
            if face.n_nodes > nv:
                phi_v = _vertex_basis(face, face.nodes[nv:])
                local[nv:] = phi_v @ local[:nv]
        if in_plane_jitter:
            local = local + in_plane_jitter * rng.uniform(-1, 1, local.shape)
        d = GDIM[face.name]
        local = np.concatenate([local, np.zeros((len(local), 1))], axis=1)  # the plane
        Q = random_rotation(rng, d)
        out.append(local @ Q.T + 0.5 * rng.uniform(-1, 1, d))
    return np.array(out)


def _vertex_basis(face: FaceType, pts: np.ndarray) -> np.ndarray:
    """Linear (simplex) or bilinear/linear (tensor) vertex basis at ``pts``."""
    lower = {"L3": "L2", "T6": "T3", "Q9": "Q4"}.get(face.name, face.name)
    return FACE_TYPES[lower].evaluate(pts)[0]


def random_interior_xi(face: FaceType, n: int, rng: np.random.Generator,
                       margin: float = 0.15) -> np.ndarray:
    """Random parametric points well inside the face."""
    if face.simplex:
        bary = rng.dirichlet(np.ones(3), n)
        bary = margin + (1 - 3 * margin) * bary
        return bary[:, 1:]
    return rng.uniform(-1 + margin, 1 - margin, (n, face.fdim))


def surface_point(face: FaceType, x_face: np.ndarray, xi: np.ndarray):
    """Point q(xi), unit normal n(xi) and tangents q_,a of faces (n, nn, d) at xi (n, fdim)."""
    phi, dphi, _ = face.evaluate(xi)
    q = np.einsum("nk,nkd->nd", phi, x_face)
    qa = np.einsum("nka,nkd->nad", dphi, x_face)
    m = surface_vector(qa)
    return q, m / np.linalg.norm(m, axis=1)[:, None], qa


# --------------------------------------------------------------------------- penetrations
def clearances(law_name: str, state: str, n: int, rng: np.random.Generator) -> np.ndarray:
    """Clearances ``g_N`` in a smooth region of the law (no table breakpoint, no cap),
    inside every cutoff (A_p >= 0.25) for ``state == "open"``."""
    if state == "open":
        return rng.uniform(1e-4, 4e-4, n)
    if law_name == "tabular":
        x = np.asarray(LAWS["tabular"].overclosures)
        seg = rng.integers(1, len(x) - 1, n)  # segments with d > 0
        lo, hi = x[seg] + 5e-4, x[seg + 1] - 5e-4
        return -(lo + (hi - lo) * rng.uniform(0, 1, n))
    return -rng.uniform(0.004, 0.025, n)


# --------------------------------------------------------------------------- cases
@dataclass
class Case:
    """A batch of contact elements with everything needed to evaluate them."""

    params: ContactParameters
    area: np.ndarray
    X_slave: np.ndarray
    u_slave: np.ndarray
    X_master: np.ndarray  # (n, nn, d) face nodes, or (n, 1, d) rigid reference point
    u_master: np.ndarray
    face: Optional[FaceType] = None
    rigid: Optional[dict] = None
    history: Optional[FrictionState] = None
    xi_exact: Optional[np.ndarray] = None  # the constructed projection point
    g_exact: Optional[np.ndarray] = None  # the constructed clearance
    tangent: str = "consistent"
    info: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(self.area)

    @property
    def d(self) -> int:
        return self.X_slave.shape[1]

    @property
    def n_nodes(self) -> int:
        return self.X_master.shape[1] + 1

    def u_e(self) -> np.ndarray:
        """Element displacements (n, nodes, d), master nodes first, slave last."""
        return np.concatenate([self.u_master, self.u_slave[:, None]], axis=1)

    def x_e(self, u_e: Optional[np.ndarray] = None) -> np.ndarray:
        u_e = self.u_e() if u_e is None else u_e
        X = np.concatenate([self.X_master, self.X_slave[:, None]], axis=1)
        return X + u_e

    def kinematics(self, u_e: Optional[np.ndarray] = None,
                   tangent: Optional[str] = None) -> Kinematics:
        u_e = self.u_e() if u_e is None else u_e
        if self.rigid is not None:
            return rigid_kinematics(self.rigid["shape"], self.X_slave, u_e[:, -1], u_e[:, 0],
                                    **{k: v for k, v in self.rigid.items() if k != "shape"})
        return face_kinematics(self.face, self.X_slave, u_e[:, -1], self.X_master, u_e[:, :-1],
                               tangent=tangent or self.tangent)

    def evaluate(self, u_e: Optional[np.ndarray] = None, params: Optional[ContactParameters] = None,
                 history: Optional[FrictionState] = "same", tangent: Optional[str] = None
                 ) -> ElementResult:
        params = self.params if params is None else params
        history = self.history if isinstance(history, str) else history
        return evaluate(self.kinematics(u_e, tangent), self.area, params, history)

    def residual(self, u_e: np.ndarray) -> np.ndarray:
        return self.evaluate(u_e).f

    def with_(self, **kw) -> "Case":
        return replace(self, **kw)


def make_params(law_name: str, state: str, tangent: str = "consistent",
                law: Optional[Law] = None) -> ContactParameters:
    mu = MU if state in ("stick", "slip") else 0.0
    return ContactParameters(LAWS[law_name] if law is None else law, mu, STICK_SLOPE, tangent)


def make_history(case: Case, ratio: np.ndarray, rng: np.random.Generator,
                 normal_part: float = 0.2, size: float = 0.01) -> FrictionState:
    """History ``(w_n, g_T_n, g_p_n)`` such that ``|F_tr| = ratio * mu |F_N|``.

    ``s = w - w_n`` and ``g_T_n`` are random of size ``size`` (s has a normal
    part too); the trial direction has a small normal component (``g_T`` is
    not re-projected onto the tangent plane, §10.12).
    """
    kin = case.kinematics()
    n, d = kin.normal.shape
    F_N, _ = case.params.law.normal_force(kin.g_N, case.area)
    s = size * rng.uniform(-1, 1, (n, d))
    w_n = kin.w - s
    g_T_n = size * rng.uniform(-1, 1, (n, d))
    nrm = kin.normal
    s_N = np.einsum("nd,nd->n", s, nrm)
    g_T = g_T_n + s - s_N[:, None] * nrm
    t = rng.standard_normal((n, d))
    t -= np.einsum("nd,nd->n", t, nrm)[:, None] * nrm
    t /= np.linalg.norm(t, axis=1)[:, None]
    t += normal_part * rng.uniform(-1, 1, n)[:, None] * nrm
    t /= np.linalg.norm(t, axis=1)[:, None]
    K_t = case.params.stick_slope * case.area
    g_p_n = g_T - (ratio * case.params.mu * np.abs(F_N) / K_t)[:, None] * t
    return FrictionState(w_n, g_T_n, g_p_n)


def state_ratio(state: str, n: int, rng: np.random.Generator) -> np.ndarray:
    if state == "stick":
        return rng.uniform(0.3, 0.7, n)
    return rng.uniform(1.5, 3.0, n)


def face_case(face_name: str, law_name: str = "linear", state: str = "frictionless", n: int = 8,
              seed=0, *, deform: float = 0.05, tangent: str = "consistent",
              g_N: Optional[np.ndarray] = None, law: Optional[Law] = None,
              rigid_master_motion: bool = False, warp: float = 0.15, jitter: float = 0.06,
              ratio: Optional[np.ndarray] = None, history_size: float = 0.01) -> Case:
    """``n`` random elements of one face type in a given law/state.

    ``deform``: size of the random master and slave displacements (the
    reference coordinates are ``current - u``); ``rigid_master_motion``: all
    master nodes get the same displacement.
    """
    rng = rng_for(face_name, law_name, state, n, seed)
    face = FACE_TYPES[face_name]
    d = GDIM[face_name]
    x_face = random_faces(face, n, rng, warp=warp, jitter=jitter)
    if rigid_master_motion:
        u_face = np.repeat(deform * rng.uniform(-1, 1, (n, 1, d)), face.n_nodes, axis=1)
    else:
        u_face = deform * rng.uniform(-1, 1, x_face.shape)
    xi = random_interior_xi(face, n, rng)
    q, nrm, _ = surface_point(face, x_face, xi)
    g = clearances(law_name, state, n, rng) if g_N is None else np.asarray(g_N, float)
    p = q + g[:, None] * nrm
    u_slave = deform * rng.uniform(-1, 1, (n, d))
    case = Case(make_params(law_name, state, tangent, law), rng.uniform(0.25, 0.5, n),
                p - u_slave, u_slave, x_face - u_face, u_face, face=face, xi_exact=xi,
                g_exact=g, tangent=tangent)
    if case.params.mu > 0:
        r = state_ratio(state, n, rng) if ratio is None else np.asarray(ratio, float)
        case.history = make_history(case, r, rng, size=history_size)
    return case


RIGID_SHAPES = ("plane3", "plane2", "sphere", "circle", "cylinder")


def rigid_case(shape: str, law_name: str = "linear", state: str = "frictionless", n: int = 8,
               seed=0, deform: float = 0.05, g_N: Optional[np.ndarray] = None) -> Case:
    """``n`` slave nodes against one rigid obstacle translated by ``U`` (stored per pair)."""
    rng = rng_for("rigid", shape, law_name, state, n, seed)
    d = 2 if shape in ("plane2", "circle") else 3
    U = np.repeat(deform * rng.uniform(-1, 1, (1, d)), n, axis=0)
    g = clearances(law_name, state, n, rng) if g_N is None else np.asarray(g_N, float)
    if shape.startswith("plane"):
        nrm = rng.standard_normal(d)
        nrm /= np.linalg.norm(nrm)
        point = rng.uniform(-0.5, 0.5, d)
        tang = rng.uniform(-1, 1, (n, d))
        tang -= (tang @ nrm)[:, None] * nrm
        x = point + U + tang + g[:, None] * nrm
        geom = dict(shape="plane", point=point, normal=nrm * rng.uniform(0.5, 2.0))
    elif shape in ("sphere", "circle"):
        center = rng.uniform(-0.5, 0.5, d)
        radius = rng.uniform(0.5, 1.5)
        dirs = rng.standard_normal((n, d))
        dirs /= np.linalg.norm(dirs, axis=1)[:, None]
        x = center + U + (radius + g)[:, None] * dirs
        geom = dict(shape="sphere", center=center, radius=radius)
    elif shape == "cylinder":
        point = rng.uniform(-0.5, 0.5, d)
        axis = rng.standard_normal(d)
        axis /= np.linalg.norm(axis)
        radius = rng.uniform(0.5, 1.5)
        dirs = rng.standard_normal((n, d))
        dirs -= (dirs @ axis)[:, None] * axis
        dirs /= np.linalg.norm(dirs, axis=1)[:, None]
        x = (point + U + rng.uniform(-1, 1, n)[:, None] * axis
             + (radius + g)[:, None] * dirs)
        geom = dict(shape="cylinder", point=point, axis=axis * rng.uniform(0.5, 2.0),
                    radius=radius)
    else:
        raise ValueError(shape)
    u_slave = deform * rng.uniform(-1, 1, (n, d))
    X_ref = np.zeros((n, 1, d))  # the obstacle's reference point (only its motion U matters)
    case = Case(make_params(law_name, state), rng.uniform(0.25, 0.5, n), x - u_slave, u_slave,
                X_ref, U[:, None].copy(), rigid=geom, g_exact=g)
    if case.params.mu > 0:
        case.history = make_history(case, state_ratio(state, n, rng), rng)
    return case


# --------------------------------------------------------------------------- finite differences
def fd_jacobian(residual: Callable[[np.ndarray], np.ndarray], u_e: np.ndarray,
                h: float = H) -> np.ndarray:
    """Central-difference Jacobian (n, nodes, d, nodes, d) of ``residual(u_e)`` (n, nodes, d).

    All pairs are perturbed at once; the loop runs over the ``nodes * d``
    perturbation directions only.
    """
    n, nodes, d = u_e.shape
    J = np.empty((n, nodes, d, nodes, d))
    for i in range(nodes):
        for l in range(d):
            up = u_e.copy()
            um = u_e.copy()
            up[:, i, l] += h
            um[:, i, l] -= h
            J[:, :, :, i, l] = (residual(up) - residual(um)) / (2.0 * h)
    return J


def rel_error(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Per-pair ``max|A - B| / max|B|`` (max over all but the first axis)."""
    n = len(A)
    num = np.abs(A - B).reshape(n, -1).max(axis=1)
    den = np.abs(B).reshape(n, -1).max(axis=1)
    return num / den


def fd_error(case: Case, h: float = H, res: Optional[ElementResult] = None) -> np.ndarray:
    """Per-pair relative error of the element tangent against central differences."""
    res = case.evaluate() if res is None else res
    J = fd_jacobian(case.residual, case.u_e(), h)
    return rel_error(res.K, J)
