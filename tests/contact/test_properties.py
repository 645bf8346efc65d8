"""Property tests (hypothesis): random face geometry, penetration, deformation and history
-> consistent tangent vs central differences, translation invariance (§11 #3, #9)."""
import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from .helpers import FACES, LAW_NAMES, face_case, fd_error, record

SETTINGS = settings(max_examples=40, derandomize=True, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.too_slow])


@st.composite
def cases(draw):
    name = draw(st.sampled_from(FACES))
    law = draw(st.sampled_from(LAW_NAMES))
    state = draw(st.sampled_from(["open", "frictionless", "stick", "slip"]))
    seed = draw(st.integers(0, 2**31 - 1))
    warp = draw(st.floats(0.0, 0.3))
    jitter = draw(st.floats(0.0, 0.08))
    deform = draw(st.floats(0.0, 0.1))
    hsize = draw(st.floats(1e-4, 0.05))
    ratio = None
    if state == "stick":
        ratio = np.full(4, draw(st.floats(0.05, 0.9)))
    elif state == "slip":
        ratio = np.full(4, draw(st.floats(1.1, 5.0)))
    return face_case(name, law, state, n=4, seed=seed, warp=warp, jitter=jitter, deform=deform,
                     ratio=ratio, history_size=hsize), (name, law, state)


@SETTINGS
@given(cases())
def test_property_tangent_matches_finite_differences(c):
    case, (name, law, state) = c
    kin = case.kinematics()
    assert kin.projection.interior.all()
    err = fd_error(case).max()
    record(f"hypothesis FD rel error [{name}]", err)
    assert err <= 1e-7, (name, law, state, err)


@SETTINGS
@given(cases(), st.lists(st.floats(-20.0, 20.0), min_size=3, max_size=3))
def test_property_translation_invariance(c, shift):
    case, (name, law, state) = c
    res = case.evaluate()
    assert np.abs(res.f.sum(axis=1)).max() <= 1e-14 * np.abs(res.f).max()
    assert np.abs(res.K.sum(axis=3)).max() <= 1e-14 * np.abs(res.K).max()
    assert np.abs(res.K.sum(axis=1)).max() <= 1e-14 * np.abs(res.K).max()
    # moving the whole configuration (reference coordinates) changes nothing but round-off
    c_ = np.asarray(shift[: case.d])
    moved = case.with_(X_master=case.X_master + c_, X_slave=case.X_slave + c_)
    res2 = moved.evaluate()
    scale = 1 + np.abs(c_).max()
    err_f = np.abs(res2.f - res.f).max() / np.abs(res.f).max()
    err_K = np.abs(res2.K - res.K).max() / np.abs(res.K).max()
    record("hypothesis |f(X + c) - f(X)| / |f| / (1 + |c|)", err_f / scale)
    record("hypothesis |K(X + c) - K(X)| / |K| / (1 + |c|)", err_K / scale)
    # round-off of coordinates of size |c| (measured <= 1.2e-14 (1 + |c|))
    assert err_f <= 1e-12 * scale and err_K <= 1e-12 * scale
    np.testing.assert_array_equal(res2.status, res.status)
