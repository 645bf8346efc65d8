"""Pressure-overclosure laws, cutoffs (§4.1, §4.2, §11 #13) and the radial return (§6, §7.1)."""
import numpy as np
import pytest

from dolfinx_friction.contact.friction import FrictionState, radial_return, tangent
from dolfinx_friction.contact.laws import Exponential, Linear, Tabular

from .helpers import LAWS, record, rng_for

_D = {  # overclosures d per law, in smooth parts (no table breakpoint, below the e^23 cap)
    "linear": np.concatenate([np.linspace(-0.05, 0.05, 41), [-1e-5, 1e-5, 0.3]]),
    "exponential": np.linspace(-0.05, 0.2, 41),
    "tabular": np.concatenate([np.linspace(-0.0018, -0.0002, 5), np.linspace(0.0005, 0.0055, 5),
                               np.linspace(0.0065, 0.0155, 5), np.linspace(0.0165, 0.0295, 5),
                               [-0.01, -0.003, 0.031, 0.1]]),
}


@pytest.mark.parametrize("name", list(LAWS))
def test_law_slopes_against_finite_differences(name):
    """§11 #13: p'(d) and dF_N/dg_N against central differences of p and F_N."""
    law = LAWS[name]
    d = _D[name]
    h = 1e-8
    p, dp = law.pressure(d)
    fd = (law.pressure(d + h)[0] - law.pressure(d - h)[0]) / (2 * h)
    scale = np.abs(dp).max()
    err = np.abs(fd - dp).max() / scale
    record(f"law dp/dd vs FD rel error [{name}]", err)
    assert err < 1e-8  # measured <= 6.2e-10 (round-off eps |p| / h relative to max|p'|)
    area = np.full_like(d, 0.37)
    F, dF = law.normal_force(-d, area)
    np.testing.assert_allclose(F, area * p, rtol=1e-15, atol=0)
    np.testing.assert_allclose(dF, -area * dp, rtol=1e-15, atol=0)
    fdF = (law.normal_force(-d + h, area)[0] - law.normal_force(-d - h, area)[0]) / (2 * h)
    assert np.abs(fdF - dF).max() / np.abs(dF).max() < 1e-6


def test_linear_law_specifics():
    K, sig = 1e4, 3.0
    law = Linear(K=K, sigma_inf=sig)
    eps = law.eps
    assert eps == pytest.approx(np.pi * sig / K, rel=1e-15)  # eps = pi sigma_inf / K (§10.14)
    p0, dp0 = law.pressure(np.array([0.0]))
    assert p0[0] == 0.0
    assert dp0[0] == pytest.approx(K / 2, rel=1e-15)
    # tension plateau: p = -sigma_inf (1 - 1/(3 z^2) + ...), z = d / eps -> -inf
    z = -1e4
    p, dp = law.pressure(np.array([z * eps]))
    assert abs(p[0] / sig + 1) < 1e-8
    assert 0 < dp[0] < 1e-8 * K
    # far in compression: p = K d - sigma_inf + O(sigma_inf / z^2)
    z = 1e3
    p, _ = law.pressure(np.array([z * eps]))
    assert abs(p[0] - (K * z * eps - sig)) < 1e-6 * sig
    # monotone with a positive slope everywhere
    d = np.linspace(-0.1, 0.1, 20001)
    p, dp = law.pressure(d)
    assert np.all(np.diff(p) > 0) and np.all(dp > 0)
    # F_N = A p(-g_N): open gaps inside the cutoff carry a small tension
    F, dF = law.normal_force(np.array([2e-4]), np.array([0.5]))
    assert -0.5 * sig < F[0] < 0 and dF[0] < 0


def test_tabular_law_specifics():
    law = LAWS["tabular"]
    P = np.array(law.pressures)
    D = np.array(law.overclosures)
    # through the table points, with the slope of the segment to their right
    p, dp = law.pressure(D)
    np.testing.assert_allclose(p, P, rtol=0, atol=1e-12)
    seg = np.diff(P) / np.diff(D)
    np.testing.assert_allclose(dp[:-1], seg, rtol=1e-13)
    # linear between points
    mid = 0.5 * (D[:-1] + D[1:])
    np.testing.assert_allclose(law.pressure(mid)[0], 0.5 * (P[:-1] + P[1:]), rtol=1e-14)
    # constant outside the table: p_1 below d_1, p_N at and above d_N, slope 0
    p, dp = law.pressure(np.array([D[0] - 1.0, D[0] - 1e-9, D[-1], D[-1] + 1e-9, 10.0]))
    np.testing.assert_array_equal(p, [P[0], P[0], P[-1], P[-1], P[-1]])
    np.testing.assert_array_equal(dp, 0.0)
    # a first point with p_1 != 0 applies p_1 everywhere in the open region (§10.9)
    law2 = Tabular(pressures=(2.0, 10.0), overclosures=(0.0, 0.01))
    assert law2.pressure(np.array([-0.5]))[0][0] == 2.0
    # consecutive overclosures are forced at least 1e-10 apart (CalculiX)
    law3 = Tabular(pressures=(0.0, 1.0, 2.0), overclosures=(0.0, 0.0, 1.0))
    assert law3.overclosures[1] - law3.overclosures[0] == pytest.approx(1e-10, rel=1e-6)
    p, dp = law3.pressure(np.array([0.5]))
    assert np.isfinite(p).all() and np.isfinite(dp).all()


def test_exponential_law_specifics():
    c0, p0 = 0.05, 10.0
    law = Exponential(c0=c0, p0=p0)
    assert law.beta == pytest.approx(np.log(100.0) / c0, rel=1e-15)
    # p0 at zero overclosure, p0/100 at clearance c0
    p, dp = law.pressure(np.array([0.0, -c0]))
    np.testing.assert_allclose(p, [p0, p0 / 100], rtol=1e-14)
    np.testing.assert_allclose(dp, law.beta * p, rtol=1e-15)
    # overflow cap: F_N = e^23 beyond beta d = 23 - ln(A p0), constant, zero slope (§4.1;
    # deliberately the exact zero, not CalculiX's -beta' F_N, §10.10)
    A = np.full(5, 0.4)
    d_cap = (23.0 - np.log(0.4 * p0)) / law.beta
    d = d_cap * np.array([0.999, 1.001, 1.5, 3.0, 100.0])
    F, dF = law.normal_force(-d, A)
    assert F[0] < np.exp(23.0) and dF[0] < 0
    np.testing.assert_array_equal(F[1:], np.exp(23.0))
    np.testing.assert_array_equal(dF[1:], 0.0)
    # the cap is continuous in F_N
    F_below, _ = law.normal_force(-np.array([d_cap * (1 - 1e-12)]), A[:1])
    assert F_below[0] == pytest.approx(np.exp(23.0), rel=1e-9)
    # p0 < 1e-30 (and p0 = 0) gives zero force everywhere, including deep penetration
    for tiny in (0.0, 1e-31):
        F, dF = Exponential(c0=c0, p0=tiny).normal_force(-np.array([0.01, 1.0, 10.0]), A[:3])
        np.testing.assert_array_equal(F, 0.0)
        np.testing.assert_array_equal(dF, 0.0)


def test_cutoffs():
    """§4.2: linear c0 sqrt(A) (c0 default 1e-3), tabular 1e-3 sqrt(A), exponential c0,
    any law with A_p = 0: 1e-10."""
    A = np.array([0.0, 0.25, 4.0])
    np.testing.assert_allclose(Linear(1e4, 3.0).cutoff(A), [1e-10, 0.5e-3, 2e-3], rtol=1e-15)
    np.testing.assert_allclose(Linear(1e4, 3.0, c0=0.02).cutoff(A), [1e-10, 0.01, 0.04],
                               rtol=1e-15)
    np.testing.assert_allclose(LAWS["tabular"].cutoff(A), [1e-10, 0.5e-3, 2e-3], rtol=1e-15)
    np.testing.assert_allclose(Exponential(c0=0.05, p0=1.0).cutoff(A), [1e-10, 0.05, 0.05],
                               rtol=1e-15)


# --------------------------------------------------------------------------- radial return
def test_radial_return_stick_slip_and_threshold():
    K_t = np.array([10.0, 10.0, 10.0, 10.0, 10.0])
    F_N = np.array([1.0, 1.0, 1.0, -1.0, 0.0])
    mu = 0.5
    g_p = np.zeros((5, 3))
    g_T = np.array([[0.01, 0, 0],        # |F_tr| = 0.1 < 0.5: stick
                    [0.05, 0, 0],        # |F_tr| = 0.5 = mu|F_N|: slip (strict stick test)
                    [0.0, 0.2, 0],       # |F_tr| = 2 > 0.5: slip
                    [0.0, 0.0, 0.2],     # tension: the limit uses |F_N|
                    [0.0, 0.0, 0.0]])    # zero trial force and zero limit: stick
    rm = radial_return(g_T, g_p, K_t, mu, F_N)
    np.testing.assert_array_equal(rm.slip, [False, True, True, True, False])
    np.testing.assert_array_equal(rm.F_T[0], [0.1, 0, 0])
    np.testing.assert_array_equal(rm.dgamma[[0, 4]], 0.0)
    assert rm.dgamma[1] == 0.0  # on the cone: slip with zero increment
    np.testing.assert_allclose(rm.F_T[1:4], [[0.5, 0, 0], [0, 0.5, 0], [0, 0, 0.5]], rtol=1e-15)
    np.testing.assert_allclose(rm.dgamma[2:4], (2.0 - 0.5) / 10.0, rtol=1e-15)
    np.testing.assert_allclose(rm.g_p[2], [0, 0.15, 0], rtol=1e-15)
    np.testing.assert_array_equal(rm.F_T[4], 0.0)
    # inputs are not modified
    np.testing.assert_array_equal(g_p, 0.0)


def test_return_map_tangent_against_finite_differences():
    """§7.1: dF_T/dg_T and dF_T/dF_N (with sign(F_N)) of the return map, stick and slip."""
    rng = rng_for("rm-tangent")
    n, d = 40, 3
    K_t = rng.uniform(5, 20, n)
    F_N = rng.uniform(0.5, 2, n) * np.where(np.arange(n) % 4 == 3, -1, 1)
    mu = 0.3
    g_p = rng.uniform(-0.05, 0.05, (n, d))
    direction = rng.standard_normal((n, d))
    direction /= np.linalg.norm(direction, axis=1)[:, None]
    ratio = np.where(np.arange(n) % 2 == 0, 0.5, 2.5)
    g_T = g_p + (ratio * mu * np.abs(F_N) / K_t)[:, None] * direction
    rm = radial_return(g_T, g_p, K_t, mu, F_N)
    np.testing.assert_array_equal(rm.slip, ratio > 1)
    # "element" with one node whose dofs are g_T itself, plus the F_N dependence
    G = np.broadcast_to(np.eye(d)[None, :, None, :], (n, d, 1, d)).copy()
    dFN = np.zeros((n, 1, d))
    T = tangent(rm, K_t, mu, F_N, G, dFN)[:, :, 0, :]
    h = 1e-7
    fd = np.empty((n, d, d))
    for l in range(d):
        e = np.zeros(d)
        e[l] = h
        fd[:, :, l] = (radial_return(g_T + e, g_p, K_t, mu, F_N).F_T
                       - radial_return(g_T - e, g_p, K_t, mu, F_N).F_T) / (2 * h)
    err = np.abs(T - fd).max() / np.abs(T).max()
    record("return map dF_T/dg_T vs FD rel error", err)
    assert err < 1e-7
    # dF_T/dF_N: G = 0 and dF_N/du = 1 (one scalar "dof")
    T2 = tangent(rm, K_t, mu, F_N, np.zeros((n, d, 1, 1)), np.ones((n, 1, 1)))[:, :, 0, 0]
    fd2 = (radial_return(g_T, g_p, K_t, mu, F_N + h).F_T
           - radial_return(g_T, g_p, K_t, mu, F_N - h).F_T) / (2 * h)
    err2 = np.abs(T2 - fd2).max() / np.abs(fd2).max()
    record("return map dF_T/dF_N vs FD rel error", err2)
    assert err2 < 1e-7
    np.testing.assert_array_equal(T2[~rm.slip], 0.0)


def test_friction_state_helpers():
    s = FrictionState.zeros(4, 2)
    assert s.w.shape == s.g_T.shape == s.g_p.shape == (4, 2)
    c = s.copy()
    c.w[:] = 1.0
    assert np.all(s.w == 0)
    sub = FrictionState(np.ones((2, 2)), 2 * np.ones((2, 2)), 3 * np.ones((2, 2)))
    s.put(np.array([1, 3]), sub)
    t = s.take(np.array([3]))
    np.testing.assert_array_equal(t.g_p, [[3.0, 3.0]])
    np.testing.assert_array_equal(s.w[[0, 2]], 0.0)
