"""§11 #12: the 1D frictional hysteresis loop against its closed form.

A flat, fixed master (every face type, randomly rotated and translated), a slave
at constant penetration, driven along a tangent t: 0 -> x_max -> -x_max -> x_max
in small steps, committing the trial state after each step (a converged
increment).  Elastic-perfectly-plastic spring: F_T = K_t x up to mu F_N, plateau,
unloading with slope K_t, reverse plateau at -mu F_N, reloading, plateau; the
slip part g_p changes only on the plateaus.
"""
import numpy as np
import pytest

from dolfinx_friction.contact.element import (
    SLIP,
    STICK,
    ContactParameters,
    evaluate,
    face_kinematics,
)
from dolfinx_friction.contact.friction import FrictionState
from dolfinx_friction.contact.shapes import FACE_TYPES

from .helpers import (
    FACES,
    GDIM,
    LAWS,
    planar_layout,
    random_rotation,
    record,
    rng_for,
    surface_point,
)

MU, LAM, AREA, DEPTH = 0.3, 100.0, 0.5, 0.01
X_MAX, DX = 0.6, 0.02


def analytic_loop(x_path, K_t, F_lim):
    """Closed form of the loop 0 -> X_MAX -> -X_MAX -> X_MAX: (F_T, g_p) along t."""
    c = F_lim / K_t  # slip onset displacement
    F = np.empty_like(x_path)
    gp = np.empty_like(x_path)
    turn1 = int(np.argmax(x_path))  # first arrival at X_MAX
    turn2 = int(np.argmin(x_path))  # arrival at -X_MAX
    for k, x in enumerate(x_path):
        if k <= turn1:  # loading from the virgin state
            F[k] = min(K_t * x, F_lim)
            gp[k] = max(x - c, 0.0)
        elif k <= turn2:  # unloading from X_MAX
            F[k] = max(F_lim - K_t * (X_MAX - x), -F_lim)
            gp[k] = min(X_MAX - c, x + c)
        else:  # reloading from -X_MAX
            F[k] = min(-F_lim + K_t * (x + X_MAX), F_lim)
            gp[k] = max(-X_MAX + c, x - c)
    return F, gp


def path():
    n1 = int(round(X_MAX / DX))
    up = np.arange(0, n1 + 1) * DX
    down = X_MAX - np.arange(1, 2 * n1 + 1) * DX
    back = -X_MAX + np.arange(1, 2 * n1 + 1) * DX
    return np.concatenate([up, down, back])


@pytest.mark.parametrize("name", FACES)
@pytest.mark.parametrize("law", ["linear", "exponential"])
def test_hysteresis_loop(name, law):
    face = FACE_TYPES[name]
    d = GDIM[name]
    rng = rng_for("loop", name, law)
    # flat master of size 3 (triangles: legs 3, inradius 0.88 > X_MAX), rotated and moved
    local = 3.0 * planar_layout(face)
    local = np.concatenate([local, np.zeros((len(local), d - face.fdim))], axis=1)
    Q = random_rotation(rng, d)
    x_face = (local @ Q.T + rng.uniform(-1, 1, d))[None]
    u_face = np.zeros_like(x_face)
    xc = np.tile(face.centroid, (1, 1))
    q, nrm, qa = surface_point(face, x_face, xc)
    t = qa[0, 0] / np.linalg.norm(qa[0, 0])  # a unit tangent
    p0 = q - DEPTH * nrm  # constant penetration DEPTH
    params = ContactParameters(LAWS[law], MU, LAM)
    area = np.array([AREA])
    F_N0, _ = LAWS[law].normal_force(np.array([-DEPTH]), area)
    K_t = LAM * AREA
    F_lim = MU * F_N0[0]
    assert 0.05 < F_lim / K_t < 0.5 * X_MAX  # the loop has plateaus and elastic legs

    xs = path()
    hist = FrictionState(np.zeros((1, d)), np.zeros((1, d)), np.zeros((1, d)))
    F_num, gp_num, status, ktt = [], [], [], []
    for x in xs:
        u_slave = (x * t)[None]
        kin = face_kinematics(face, p0, u_slave, x_face, u_face)
        res = evaluate(kin, area, params, hist)
        # constant penetration, normal and normal force along the whole path
        assert abs(res.g_N[0] + DEPTH) < 1e-15
        assert abs(res.F_N[0] - F_N0[0]) <= 1e-13 * F_N0[0]
        # no tangential force out of the line of motion
        assert np.linalg.norm(res.F_T[0] - (res.F_T[0] @ t) * t) < 1e-13 * F_lim
        F_num.append(res.F_T[0] @ t)
        gp_num.append(res.trial.g_p[0] @ t)
        status.append(res.status[0])
        ktt.append(t @ res.K[0, -1, :, -1, :] @ t)  # slave-slave stiffness along t
        hist = res.trial  # commit (converged increment)
    F_num, gp_num, status, ktt = map(np.array, (F_num, gp_num, status, ktt))
    F_ref, gp_ref = analytic_loop(xs, K_t, F_lim)
    errF = np.abs(F_num - F_ref).max() / F_lim
    errg = np.abs(gp_num - gp_ref).max() / X_MAX
    record(f"#12 hysteresis |F_T - analytic| / (mu F_N) [{name}]", errF)
    record(f"#12 hysteresis |g_p - analytic| / x_max [{name}]", errg)
    assert errF < 1e-12 and errg < 1e-12  # measured <= 6.6e-14 / 3.2e-14 (300 commits)
    # stick on the elastic legs, slip on the plateaus
    on_plateau = np.abs(np.abs(F_ref) - F_lim) < 1e-12 * F_lim
    elastic = np.abs(F_ref) < F_lim * (1 - 1e-9)
    assert np.all(status[elastic] == STICK) and np.all(status[on_plateau & ~elastic] == SLIP)
    # g_p changes only on the plateaus, and there by the full step
    dgp = np.abs(np.diff(gp_num))
    assert np.all(dgp[elastic[1:]] < 1e-15)
    # tangent along t: K_t in stick, 0 in slip (flat master: no normal rotation)
    assert np.allclose(ktt[status == STICK], K_t, rtol=1e-12, atol=0)
    assert np.all(np.abs(ktt[status == SLIP]) < 1e-12 * K_t)
    # the loop closes: the last point repeats the first arrival at X_MAX
    assert abs(F_num[-1] - F_lim) < 1e-12 * F_lim
    # dissipated work per cycle = the parallelogram's area 4 mu F_N (x_max - c); the
    # trapezoidal rule on the sampled loop misses only the corners cut by a step
    turn1 = int(np.argmax(xs))
    loop_x, loop_F = xs[turn1:], F_num[turn1:]
    work = np.sum(0.5 * (loop_F[1:] + loop_F[:-1]) * np.diff(loop_x))
    c = F_lim / K_t
    assert work == pytest.approx(4 * F_lim * (X_MAX - c), rel=1e-3)
