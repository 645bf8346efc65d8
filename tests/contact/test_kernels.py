"""The compiled kernels (contact/kernels.py) against the numpy reference, to round-off.

Every face type, rigid shape, law, state (open, frictionless, stick, slip) and
tangent option: kinematics, forces, tangents, statuses and the trial history
agree to 1e-12 relative (``max|a - b| / max|b|`` over the batch, per array);
booleans and statuses exactly.  The worst values are printed at the end of the
session.  The largest differences are in the clearance of open pairs (1e-4 on
coordinates of size 1: the round-off of a coordinate difference, ~1e-16 / 1e-4).
"""
from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

kernels = pytest.importorskip("dolfinx_friction.contact.kernels")

from dolfinx_friction.contact import backend  # noqa: E402
from dolfinx_friction.contact.element import (ContactParameters, evaluate,  # noqa: E402
                                              evaluate_numpy, face_kinematics_numpy,
                                              rigid_kinematics_numpy)
from dolfinx_friction.contact.laws import Exponential, Linear, Tabular  # noqa: E402
from dolfinx_friction.contact.projection import clearances_numpy, project_numpy  # noqa: E402
from dolfinx_friction.contact.shapes import FACE_TYPES  # noqa: E402

from .helpers import (FACES, LAW_NAMES, LAWS, RIGID_SHAPES, STATES, face_case,  # noqa: E402
                      random_faces, random_interior_xi, record, rigid_case, rng_for,
                      surface_point)

TOL = 1e-12
KIN_FIELDS = ("normal", "g_N", "dg_N", "dnormal", "phi", "dphi", "dxi", "w", "dw", "xi")
RESULT_FIELDS = ("f", "K", "F_N", "F_T", "g_N")


def rel(a, b) -> float:
    """``max|a - b| / max|b|`` (0 for empty arrays; ``max|a|`` if ``b`` is zero)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape
    if b.size == 0:
        return 0.0
    scale = np.abs(b).max()
    return float(np.abs(a - b).max() / (scale if scale > 0 else 1.0))


def assert_kinematics_equal(new, ref, key: str):
    for name in KIN_FIELDS:
        err = record(f"kernels: kinematics {name} [{key}]", rel(getattr(new, name),
                                                                getattr(ref, name)))
        assert err <= TOL, (name, err)
    if ref.projection is not None:
        for flag in ("converged", "interior"):
            assert np.array_equal(getattr(new.projection, flag), getattr(ref.projection, flag))


def assert_results_equal(new, ref, key: str):
    for name in RESULT_FIELDS:
        err = record(f"kernels: {name} [{key}]", rel(getattr(new, name), getattr(ref, name)))
        assert err <= TOL, (name, err)
    assert new.status.dtype == ref.status.dtype
    assert np.array_equal(new.status, ref.status)
    assert (new.trial is None) == (ref.trial is None)
    if ref.trial is not None:
        for name in ("w", "g_T", "g_p"):
            err = record(f"kernels: trial {name} [{key}]",
                         rel(getattr(new.trial, name), getattr(ref.trial, name)))
            assert err <= TOL, (name, err)


def face_pair(case, tangent):
    u = case.u_e()
    args = (case.face, case.X_slave, u[:, -1], case.X_master, u[:, :-1])
    return (kernels.face_kinematics(*args, tangent=tangent),
            face_kinematics_numpy(*args, tangent=tangent))


@pytest.mark.parametrize("tangent", ["consistent", "calculix"])
@pytest.mark.parametrize("state", STATES)
@pytest.mark.parametrize("law", LAW_NAMES)
@pytest.mark.parametrize("name", FACES)
def test_face_elements_equal_numpy(name, law, state, tangent):
    case = face_case(name, law, state, n=24, tangent=tangent)
    new, ref = face_pair(case, tangent)
    key = f"{name}"
    assert_kinematics_equal(new, ref, key)
    expected = evaluate_numpy(ref, case.area, case.params, case.history)
    assert_results_equal(kernels.evaluate(new, case.area, case.params, case.history),
                         expected, key)
    # the compiled evaluation of numpy kinematics too (callers may mix them)
    assert_results_equal(kernels.evaluate(ref, case.area, case.params, case.history),
                         expected, key)
    if state in ("stick", "slip"):
        assert np.all(expected.status == (1 if state == "stick" else 2))


@pytest.mark.parametrize("state", STATES)
@pytest.mark.parametrize("law", LAW_NAMES)
@pytest.mark.parametrize("shape", RIGID_SHAPES)
def test_rigid_elements_equal_numpy(shape, law, state):
    case = rigid_case(shape, law, state, n=24)
    u = case.u_e()
    geometry = {k: v for k, v in case.rigid.items() if k != "shape"}
    args = (case.rigid["shape"], case.X_slave, u[:, -1], u[:, 0])
    new = kernels.rigid_kinematics(*args, **geometry)
    ref = rigid_kinematics_numpy(*args, **geometry)
    assert_kinematics_equal(new, ref, "rigid")
    # U as one translation (d,), as interaction.py passes it
    one = kernels.rigid_kinematics(*args[:3], u[0, 0], **geometry)
    assert_kinematics_equal(one, rigid_kinematics_numpy(*args[:3], u[0, 0], **geometry), "rigid")
    assert_results_equal(kernels.evaluate(new, case.area, case.params, case.history),
                         evaluate_numpy(ref, case.area, case.params, case.history), "rigid")


@pytest.mark.parametrize("name", FACES)
def test_mixed_batch_with_gap_offset(name):
    """Open, stick and slip pairs in one batch, a per-pair overclosure ramp shift."""
    rng = rng_for("mixed", name)
    n = 30
    g = np.where(np.arange(n) % 3 == 0, 2e-4, -rng.uniform(0.004, 0.02, n))
    ratio = np.where(np.arange(n) % 2 == 0, 0.5, 2.0)
    case = face_case(name, "linear", "slip", n=n, g_N=g, ratio=ratio)
    new, ref = face_pair(case, "consistent")
    offset = rng.uniform(-1e-3, 1e-3, n)
    for shift in (offset, 5e-4):
        expected = evaluate_numpy(ref, case.area, case.params, case.history, gap_offset=shift)
        assert len(set(expected.status.tolist())) == 3
        assert_results_equal(kernels.evaluate(new, case.area, case.params, case.history,
                                              gap_offset=shift), expected, "mixed")


@pytest.mark.parametrize("name", FACES)
def test_projection_equal_numpy(name):
    """Cold and warm starts, points beyond the edges, and too few iterations."""
    face = FACE_TYPES[name]
    rng = rng_for("kernel projection", name)
    n = 40
    x_face = random_faces(face, n, rng)
    xi = random_interior_xi(face, n, rng, margin=-0.4)  # some beyond the edges
    q, nrm, _ = surface_point(face, x_face, xi)
    x = q + rng.uniform(-0.05, 0.05, n)[:, None] * nrm
    starts = (None, xi + 0.05 * rng.uniform(-1, 1, xi.shape))
    for xi0 in starts:
        for max_iter in (30, 1):
            new = kernels.project(face, x, x_face, xi0, max_iter=max_iter)
            ref = project_numpy(face, x, x_face, xi0, max_iter=max_iter)
            err = record(f"kernels: projection xi [{name}]", rel(new.xi, ref.xi))
            assert err <= TOL
            assert np.array_equal(new.converged, ref.converged)
            assert np.array_equal(new.interior, ref.interior)
    assert not ref.converged.any()  # one iteration: not yet converged
    full = project_numpy(face, x, x_face)
    assert full.converged.all() and not full.interior.all()
    if xi0 is not None:
        assert np.array_equal(xi0, starts[1])  # the start is not modified


def candidate_case(name: str, rng: np.random.Generator, n_points: int = 20, k: int = 4,
                   **shape) -> tuple:
    """Pairing's candidates: ``n_points`` points, each near one of 8 random faces (some
    beyond its edges, up to 0.3 off it) and paired with ``k`` faces (its own and random
    ones, in random order): ``(x, x_face, slave, faces)``."""
    face = FACE_TYPES[name]
    x_face = random_faces(face, 8, rng, **shape)
    own = rng.integers(0, 8, n_points)
    xi = random_interior_xi(face, n_points, rng, margin=-0.4)
    q, nrm, _ = surface_point(face, x_face[own], xi)
    x = q + rng.uniform(-0.3, 0.3, n_points)[:, None] * nrm
    faces = np.concatenate([own[:, None], rng.integers(0, 8, (n_points, k - 1))], axis=1)
    order = rng.permutation(n_points * k)
    return x, x_face, np.repeat(np.arange(n_points), k)[order], faces.ravel()[order]


def assert_clearances_equal(name: str, x, x_face, slave, faces, xi0) -> tuple:
    """The kernel's clearances equal the numpy reference's; returns the reference."""
    face = FACE_TYPES[name]
    start = xi0.copy()
    new = kernels.clearances(face, x, x_face, slave, faces, xi0)
    ref = clearances_numpy(face, x, x_face, slave, faces, xi0)
    assert np.array_equal(xi0, start)  # the start is not modified
    assert np.array_equal(np.isfinite(new[1]), np.isfinite(ref[1]))
    finite = np.isfinite(ref[1])
    for label, a, b in (("xi", new[0], ref[0]), ("outside", new[1][finite], ref[1][finite]),
                        ("g_N", new[2], ref[2])):
        err = record(f"kernels: clearances {label} [{name}]", rel(a, b))
        assert err <= TOL, (label, err)
    return ref


@pytest.mark.parametrize("name", FACES)
def test_clearances_equal_numpy(name):
    """Points paired with several faces (repeats, any order): cold and warm starts, points
    inside and beyond the edges."""
    face = FACE_TYPES[name]
    x, x_face, slave, faces = candidate_case(name, rng_for("kernel clearances", name))
    cold = np.tile(face.centroid, (len(slave), 1))
    xi, outside, _ = assert_clearances_equal(name, x, x_face, slave, faces, cold)
    assert (outside == 0).any() and (outside > 0.05).any()
    warm = xi + 0.01 * rng_for("warm", name).uniform(-1, 1, xi.shape)
    assert_clearances_equal(name, x, x_face, slave, faces, warm)
    none = np.zeros(0, dtype=np.int64)
    assert_clearances_equal(name, x, x_face, none, none, cold[:0])


@settings(max_examples=40, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(FACES), st.integers(0, 2**31 - 1), st.floats(0.0, 0.3),
       st.floats(0.0, 0.08))
def test_property_clearances_equal_numpy(name, seed, warp, jitter):
    x, x_face, slave, faces = candidate_case(name, np.random.default_rng(seed), warp=warp,
                                             jitter=jitter)
    cold = np.tile(FACE_TYPES[name].centroid, (len(slave), 1))
    assert_clearances_equal(name, x, x_face, slave, faces, cold)


def test_empty_batches():
    case = face_case("Q4", "linear", "slip", n=3)
    empty = slice(0, 0)
    u = case.u_e()[empty]
    kin = kernels.face_kinematics(case.face, case.X_slave[empty], u[:, -1],
                                  case.X_master[empty], u[:, :-1])
    res = kernels.evaluate(kin, case.area[empty], case.params, case.history.take(empty))
    assert res.K.shape == (0, 5, 3, 5, 3) and res.trial.g_p.shape == (0, 3)


@dataclass(frozen=True)
class _SoftLinear(Linear):
    """A law the kernels do not know: its own (numpy) normal_force is used."""

    def normal_force(self, g_N, area):
        F, dF = super().normal_force(g_N, area)
        return 0.5 * F, 0.5 * dF


def test_unknown_law_uses_its_own_method():
    case = face_case("T6", "linear", "slip", n=10)
    params = ContactParameters(_SoftLinear(K=1e4, sigma_inf=3.0), case.params.mu,
                               case.params.stick_slope)
    new, ref = face_pair(case, "consistent")
    assert_results_equal(kernels.evaluate(new, case.area, params, case.history),
                         evaluate_numpy(ref, case.area, params, case.history), "law subclass")


@pytest.mark.parametrize("law", [*LAWS.values(), Exponential(c0=0.05, p0=0.0),
                                 Tabular(pressures=(1.0, 3.0), overclosures=(0.0, 0.0))])
def test_normal_force_equal_numpy(law):
    """Across the table's breakpoints and ends, the exponential cap, zero areas."""
    d = np.concatenate([np.linspace(-0.01, 0.5, 2001), [0.0, -0.002, 0.006, 0.03]])
    area = np.concatenate([np.full(len(d) - 3, 0.3), [0.0, 0.0, 1e3]])
    F, dF = kernels.normal_force(law, -d, area)
    F_ref, dF_ref = law.normal_force(-d, area)
    assert rel(F, F_ref) <= TOL and rel(dF, dF_ref) <= TOL


def test_switch_selects_the_implementation():
    """``backend.use`` picks what ``evaluate`` runs: the numpy reference's result bit for
    bit, or the kernel's (the two differ in the last bits: which one ran shows)."""
    case = face_case("Q4", "linear", "slip", n=4)
    kin = case.kinematics()
    args = (kin, case.area, case.params, case.history)

    def same(a, b) -> bool:
        return all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("f", "K", "F_N", "F_T"))

    numpy_result, kernel_result = evaluate_numpy(*args), kernels.evaluate(*args)
    assert not same(numpy_result, kernel_result)
    with backend.use("numpy"):
        assert backend.active() == "numpy"
        assert same(evaluate(*args), numpy_result)
    with backend.use("numba"):
        assert backend.active() == "numba"
        assert same(evaluate(*args), kernel_result)
    with pytest.raises(ValueError):
        backend.use("fortran")


@pytest.mark.parametrize("choice", ["numpy", "numba"])
def test_environment_variable(choice):
    code = "from dolfinx_friction.contact import backend; print(backend.active())"
    env = dict(os.environ, **{backend.ENV: choice})
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True)
    assert out.stdout.strip() == choice


def test_jit_without_a_cache_directory():
    """A function numba cannot cache (no source file: no cache locator) still compiles."""
    namespace = {}
    exec(compile("def twice(x):\n    return 2.0 * x\n", "<no file>", "exec"), namespace)
    twice = kernels._jit(namespace["twice"])
    assert twice(1.5) == 3.0
