"""Boundaries found by the stability maps (``benchmarks/stability/``).

* A slide increment that Newton cannot take in one go (the stick -> slip transition of
  an elastic block on an elastic foundation) converges once the increment is cut back,
  with the history rolled back, and gives the full-slip answer.
* Chattering: a convex slave tip pressed into a concave V-groove flips between the two
  groove faces at every re-pairing; freezing the pairing early converges in a few
  iterations, the CalculiX default (freeze after 8) needs twice as many, and re-pairing
  in every iteration never converges, whatever the increment.
* A penalty far too soft (K = 0.01 E/h) is flagged by the penetration warning; the
  default is not.
* Sliding a whole master face per increment keeps the bodies in contact (a regression
  test for the search bound that the maps exposed).
* A penalty far too stiff (K = 10^4 E/h) turns a slide increment that converges at
  K = 10 E/h into a failure: cutbacks rescue it, and with too few cutbacks the failure
  is reported (ConvergenceError naming the increment, ``summary.json`` not converged)
  and the failed increment is never written as converged.
* The bugs the maps found stay fixed (reproducers in ``benchmarks/stability/reproducers/``):
  a soft penalty converges at the round-off floor instead of stalling; an initial
  overclosure being ramped out raises no penetration warning; pairing once per increment
  after a rate predictor keeps the contact; a node that slides past all its candidate
  faces within one increment is searched for again, and one that slides off the master
  surface is reported; a size that keeps failing is not retried after every easy increment;
  an increment in which a whole contact zone slides off the master is cut back.

All scenes are small meshes (2D but one); every test runs serially and under ``mpirun -n 2``.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from dolfinx_friction.scene.runner import PENETRATION_WARNING, run
from dolfinx_friction.scene.model import (BC, Body, ContactPair, Output, Rigid, RigidMotion, Scene,
                                    Step)
from dolfinx_friction.scene.driver import ConvergenceError
from dolfinx_friction.reference import meshes

DEMOS = Path(__file__).resolve().parents[2] / "demos"

E, NU = 1000.0, 0.3


def _converged(inc) -> bool:
    """The increment's last residual is within what the convergence test accepts:
    ``newton_rtol`` times the forces, ``newton_atol``, or the round-off floor (a stiff
    penalty's), ``inc.tolerance``; and that is a small share of the forces."""
    return inc.residuals[-1] <= inc.tolerance <= 1e-6 * inc.force


def _within_tolerances(inc, step: Step) -> bool:
    """The increment's last residual meets the step's tolerances alone (``newton_rtol``
    times the smaller of its first residual and the forces, ``newton_atol``), without the
    round-off floor."""
    target = max(step.newton_rtol * min(inc.residuals[0], inc.force), step.newton_atol)
    return inc.residuals[-1] <= target


# ----------------------------------------------------------------------------- meshes
def block_on_foundation(path, y0: float = 0.0):
    """Block [0,1] x [y0, y0 + 0.5] (8 x 4 quads) on a foundation [-0.546, 1.5] x [-0.5, 0]
    (16 x 4, master faces of the block's size, shifted by 0.37 of a face)."""
    return meshes.block_on_foundation(path, y0=y0, x_end=1.5)


# ----------------------------------------------------------------------------- scenes
def _sliding_block(mesh, slide: float, max_cutbacks: int, line_search: bool = False) -> Scene:
    """Press the block 0.01 into the foundation, then slide it by ``slide`` in one
    increment; CalculiX's penalty and stick slope (K = 50 E = 6.25 E/h, lambda = E/2: the
    defaults before scene format version 2, at which these tests were measured), mu = 0.3."""
    kw = dict(max_cutbacks=max_cutbacks, max_iterations=10, line_search=line_search)
    return Scene(
        mesh=mesh, bodies=(Body("block", E, NU), Body("foundation", E, NU)),
        contacts=(ContactPair("block_bottom", "foundation_top", mu=0.3, K="calculix",
                              stick_slope="calculix"),),
        steps=(Step("press", bcs=(BC("foundation_bottom", (0.0, 0.0)),
                                  BC("block_top", (0.0, -0.01))), **kw),
               Step("slide", bcs=(BC("block_top", (slide, -0.01)),), **kw)))


def _block_on_floor(mesh, k: float, max_cutbacks: int = 5, slide: float = 0.125,
                    output: Output = Output()) -> Scene:
    """The 8 x 2 rectangle pressed 0.005 onto a rigid floor, then slid by ``slide`` (one
    slave spacing) in one increment; K = k E/h with h = 1/8, mu = 0.3."""
    kw = dict(max_cutbacks=max_cutbacks, max_iterations=10)
    return Scene(
        mesh=mesh, bodies=(Body("block", E, NU),),
        rigids=(Rigid("floor", "plane", point=(0.0, 0.0), normal=(0.0, 1.0)),),
        contacts=(ContactPair("bottom", "floor", mu=0.3, K=k * E * 8),),
        steps=(Step("press", bcs=(BC("top", (0.0, -0.005)),), **kw),
               Step("slide", bcs=(BC("top", (slide, -0.005)),), **kw)),
        output=output)


# ------------------------------------------------------------------------------ tests
def test_cutback_rescues_stick_slip_transition(shared_dir):
    """Block on foundation, slide 0.05 (0.4 face) in one increment: Newton cycles without
    converging (stick -> slip of all nodes at once); halving the increment converges and
    the rolled-back history gives the answer of the smaller increments."""
    mesh = block_on_foundation(shared_dir / "block.msh")
    with pytest.raises(ConvergenceError, match=r"step 1 \('slide'\), increment 1 .* 0 cutbacks"):
        run(_sliding_block(mesh, 0.05, max_cutbacks=0), write=False)
    scene = _sliding_block(mesh, 0.05, max_cutbacks=5)
    result = run(scene, write=False)
    assert result.summary.converged and result.summary.cutbacks >= 1
    incs = result.increments
    assert incs[-1].t == pytest.approx(2.0)
    assert all(_converged(inc) for inc in incs)
    assert incs[-1].active == 9
    R = incs[-1].reactions["block_top"]
    assert abs(R[0] / R[1]) == pytest.approx(0.3, rel=0.02)  # (nearly) full slip
    # the same smaller increments, asked for directly, give the same state
    n = sum(1 for inc in incs if inc.step == 1)
    direct = run(Scene(mesh=scene.mesh, bodies=scene.bodies, contacts=scene.contacts,
                       steps=(scene.steps[0], Step("slide", increments=n,
                                                   bcs=scene.steps[1].bcs))), write=False)
    np.testing.assert_allclose(direct.increments[-1].reactions["block_top"], R, rtol=1e-8)
    # the default line search takes the increment in one go
    searched = run(_sliding_block(mesh, 0.05, max_cutbacks=0, line_search=True), write=False)
    R = searched.increments[-1].reactions["block_top"]
    assert searched.summary.cutbacks == 0 and abs(R[0] / R[1]) == pytest.approx(0.3, rel=0.02)


def test_slide_of_a_whole_face_keeps_contact(shared_dir):
    """Sliding one master face in one increment must not uncouple the bodies.  (Before the
    search dropped its distance bound, each slave node had only two candidate faces, lost
    them all within the increment, and the increment was accepted with no contact and a
    zero reaction: benchmarks/stability/README.md.)"""
    mesh = block_on_foundation(shared_dir / "block.msh")
    result = run(_sliding_block(mesh, 0.125, max_cutbacks=5), write=False)
    for inc in result.increments:
        assert inc.active == 9
        assert -inc.reactions["block_top"][1] > 10.0


def _groove_scene(mesh, pairing_iterations: int, max_cutbacks: int = 0,
                  max_iterations: int = 30) -> Scene:
    return Scene(
        mesh=mesh, bodies=(Body("block", E, NU), Body("foundation", E, NU)),
        contacts=(ContactPair("tip", "groove", K=10.0 * E / 0.0625,
                              pairing_iterations=pairing_iterations),),
        steps=(Step("press", max_cutbacks=max_cutbacks, max_iterations=max_iterations,
                    bcs=(BC("foundation_bottom", (0.0, 0.0)), BC("block_top", (0.0, -0.005)))),))


def test_pairing_freeze_stops_face_chattering(shared_dir):
    """The tip node in a concave V-groove is pushed by each groove face towards the other:
    re-paired in every iteration it alternates between the two faces for ever; with the
    pairing frozen it converges on one of them."""
    mesh = meshes.tip_in_groove(shared_dir / "groove.msh")
    frozen = run(_groove_scene(mesh, 2), write=False)
    inc = frozen.increments[-1]
    assert inc.active == 1 and inc.iterations <= 6
    assert -inc.reactions["block_top"][1] > 1.0  # the tip carries the press
    default = run(_groove_scene(mesh, 8), write=False)  # CalculiX: freeze after 8
    assert default.increments[-1].iterations >= 9  # chattered until the freeze
    with pytest.raises(ConvergenceError):
        run(_groove_scene(mesh, 10_000, max_cutbacks=1, max_iterations=15), write=False)


def test_too_soft_penalty_warns(shared_dir, caplog):
    """K = 0.01 E/h lets the block sink 8 % of its node spacing into the floor: warned,
    also in summary.json; the default K (6.25 E/h) is not."""
    mesh = meshes.rectangle_2d(shared_dir / "rect.msh", n=(8, 2))
    comm = MPI.COMM_WORLD
    out = shared_dir / "soft"
    soft = run(_block_on_floor(mesh, 0.01, output=Output(fields=False)), out=out)
    worst = max(inc.penetration["bottom->floor"] for inc in soft.increments)
    assert worst > PENETRATION_WARNING
    err = caplog.text  # logged (the command line prints it), from rank 0
    if comm.rank == 0:
        assert "too soft" in err and "bottom->floor" in err
        summary = json.loads((out / "summary.json").read_text())
        assert summary["converged"] and any("too soft" in w for w in summary["warnings"])
    caplog.clear()
    default = run(_block_on_floor(mesh, 6.25), write=False)
    assert max(inc.penetration["bottom->floor"] for inc in default.increments) < PENETRATION_WARNING
    assert "too soft" not in caplog.text


def test_too_stiff_penalty_cut_back_or_reported(shared_dir):
    """Slide by one spacing in one increment: fine at K = 10 E/h; at K = 10^4 E/h Newton
    fails, two cutbacks recover it, and with one cutback only the run stops with a report
    and writes only the converged increments."""
    mesh = meshes.rectangle_2d(shared_dir / "rect.msh", n=(8, 2))
    moderate = run(_block_on_floor(mesh, 10.0, max_cutbacks=0), write=False)
    assert moderate.summary.cutbacks == 0
    stiff_scene = _block_on_floor(mesh, 1e4, max_cutbacks=5)
    stiff = run(stiff_scene, write=False)
    assert stiff.summary.cutbacks >= 1
    assert all(_converged(inc) for inc in stiff.increments)
    last = stiff.increments[-1]
    assert last.t == pytest.approx(2.0) and last.active == last.slipping == 9
    R = last.reactions["top"]
    assert abs(R[0] / R[1]) == pytest.approx(0.3, rel=1e-8)  # full slip, as with K = 10 E/h
    out = shared_dir / "stiff"
    with pytest.raises(ConvergenceError, match=r"step 1 \('slide'\), increment 1 .* 1 cutbacks"):
        run(_block_on_floor(mesh, 1e4, max_cutbacks=1, output=Output(fields=False)), out=out)
    if MPI.COMM_WORLD.rank == 0:
        rows = (out / "history.csv").read_text().splitlines()[1:]
        assert [r.split(",")[:2] for r in rows] == [["0", "1"]]  # the press only
        summary = json.loads((out / "summary.json").read_text())
        assert summary["converged"] is False and "increment 1" in summary["failure"]


# ------------------------------------------------------------ fixed bugs of the maps
def test_soft_penalty_converges_at_roundoff(shared_dir):
    """Block on a foundation (3D), both carried 100 lengths along x while the block is
    pressed and slid, soft penalty K = 0.01 E/h: |K| |u| is large, the change per slide
    increment small, so rtol |R_0| asks for less than round-off.  The stopping test accepts
    the round-off floor (|K| |u| + contact terms) instead of failing the increment (it did:
    "residual 9.8e-09" after 0 cutbacks)."""
    mesh = meshes.two_boxes(shared_dir / "boxes.msh", (4, 4, 2), (5, 5, 2))
    E3, T = 210000.0, 100.0
    kw = dict(max_cutbacks=0)
    scene = Scene(
        mesh=mesh, bodies=(Body("block", E3, NU), Body("foundation", E3, NU)),
        contacts=(ContactPair("block_bottom", "foundation_top", mu=0.3, K=0.01 * E3 / 0.125),),
        steps=(Step("press", bcs=(BC("foundation_bottom", (T, 0.0, 0.0)),
                                  BC("block_top", (T, 0.0, -0.002))), **kw),
               Step("slide", increments=10, bcs=(BC("foundation_bottom", (2 * T, 0.0, 0.0)),
                                                 BC("block_top", (2 * T + 0.1, 0.0, -0.002))),
                    **kw)))
    result = run(scene, write=False)
    assert result.summary.converged and len(result.increments) == 11
    # the floor decided: some increment stopped above what the tolerances alone ask
    assert not all(_within_tolerances(inc, scene.steps[inc.step]) for inc in result.increments)
    assert all(_converged(inc) for inc in result.increments)
    assert all(inc.active == 25 for inc in result.increments)


def test_ramped_initial_overclosure_is_not_a_soft_penalty(shared_dir, caplog):
    """The block starts half a spacing inside the foundation; the press step ramps the
    overclosure out (docs/theory.md §3.4) and ends pressed 0.01.  The law acts on 0.36 %
    of the spacing at most, and the penetration warning must measure that, not the
    geometric overlap (75 %)."""
    mesh = block_on_foundation(shared_dir / "overlap.msh", y0=-0.0625)
    scene = Scene(
        mesh=mesh, bodies=(Body("block", E, NU), Body("foundation", E, NU)),
        contacts=(ContactPair("block_bottom", "foundation_top", mu=0.3, K=10 * E * 8),),
        steps=(Step("press", increments=4, bcs=(BC("foundation_bottom", (0.0, 0.0)),
                                                BC("block_top", (0.0, 0.0525)))),))
    result = run(scene, write=False)
    assert all(inc.active == 9 for inc in result.increments)
    assert max(inc.penetration["block_bottom->foundation_top"]
               for inc in result.increments) < 0.005
    assert "too soft" not in caplog.text


def test_pairing_once_after_a_predictor_keeps_contact(shared_dir):
    """A rigid disk pressed one spacing into a block and dragged 24 spacings in 40
    increments, paired once per increment (CalculiX's SMALL SLIDING).  The first pairing
    sees the state predicted from the last increment's rate, which can lift the nodes under
    the disk beyond the cutoff; nodes closed at the last commit keep their elements, so
    every increment keeps the contact (without that: increments with no node in contact
    and a zero force on the disk)."""
    mesh = meshes.rectangle_2d(shared_dir / "rect40.msh", n=(40, 8))
    r, depth, kw = 0.1, 0.025, dict(line_search=False)
    scene = Scene(
        mesh=mesh, bodies=(Body("block", E, NU),),
        rigids=(Rigid("die", "sphere", center=(0.2, 0.25 + r), radius=r),),
        contacts=(ContactPair("top", "die", mu=0.3, K=10 * E / 0.025, pairing_iterations=1),),
        steps=(Step("press", increments=2, bcs=(BC("bottom", (0.0, 0.0)),),
                    rigid=(RigidMotion("die", displacement=(0.0, -depth)),), **kw),
               Step("drag", increments=40,
                    rigid=(RigidMotion("die", displacement=(0.6, -depth)),), **kw)))
    result = run(scene, write=False)
    drags = [inc for inc in result.increments if inc.step == 1]
    assert drags[-1].t == pytest.approx(2.0)
    assert min(inc.active for inc in drags) >= 3
    assert max(inc.rigid_f["die"][1] for inc in drags) < -15.0


def test_slide_past_all_candidates_searches_again(shared_dir, caplog):
    """Slide the block by a whole block width (8 faces) in one increment, past the end of
    the foundation: every slave node leaves its 6 candidate faces within the first Newton
    iterations.  A new search pairs them again, so no increment is accepted without
    contact, the nodes that reach the end are reported, and 5 nodes stay on the foundation."""
    mesh = block_on_foundation(shared_dir / "block.msh")
    result = run(_sliding_block(mesh, 1.0, max_cutbacks=5, line_search=True), write=False)
    pair = "block_bottom->foundation_top"
    assert all(inc.active >= 5 for inc in result.increments)
    last = result.increments[-1]
    assert last.t == pytest.approx(2.0) and last.active == 5
    assert sum(inc.detached[pair] for inc in result.increments) == 4
    assert abs(last.reactions["block_top"][1]) > 5.0
    if MPI.COMM_WORLD.rank == 0:
        assert "slid off the master surface" in caplog.text


def test_regrowth_does_not_retry_a_failing_size(shared_dir):
    """Block slid half its width in 4 increments without line search: the first slide
    increment needs cutbacks.  Growing back after every easy increment retried the failing
    size every other increment (13 cutbacks); waiting longer after a repeated failure
    halves that."""
    mesh = block_on_foundation(shared_dir / "block.msh")
    scene = _sliding_block(mesh, 0.5, max_cutbacks=6)
    from dataclasses import replace
    scene = replace(scene, steps=(scene.steps[0], replace(scene.steps[1], increments=4)))
    result = run(scene, write=False)
    assert result.summary.converged
    assert 1 <= result.summary.cutbacks <= 8


def _coarse_ironing(path) -> Path:
    """The ironing demo's mesh, coarse (40 x 8 block elements, 16 on the die's arc), as the
    stability maps use it."""
    import importlib
    import sys
    if MPI.COMM_WORLD.rank == 0 and not path.exists():
        sys.path.insert(0, str(DEMOS))  # the demo imports its helpers (_meshing, _common)
        try:
            importlib.import_module("ironing").build_mesh(path, nx=40, ny=8, n_arc=16)
        finally:
            sys.path.remove(str(DEMOS))
    MPI.COMM_WORLD.barrier()
    return path


def _lost_zone_scene(shared_dir) -> Scene:
    """Coarse ironing, mu = 1, K = stick slope = 10 E/h, half a die element of drag per
    increment, plain Newton (the maps' ironing_stick_mu cell)."""
    from dataclasses import replace

    from dolfinx_friction.scene.toml import load_scene
    base = load_scene(DEMOS / "ironing.toml")
    h, E_block = 20.0 / 40, 10.0
    pair = replace(base.contacts[0], K=10 * E_block / h, stick_slope=10 * E_block / h, mu=1.0)
    kw = dict(max_cutbacks=5, max_iterations=30, line_search=False)
    press, drag = base.steps
    drag_bcs = tuple(replace(b, u=(4.0, *b.u[1:])) if b.on == "die_top" else b
                     for b in drag.bcs)
    return replace(base, mesh=_coarse_ironing(shared_dir / "ironing_coarse.msh"),
                   contacts=(pair,), output=Output(fields=False, contact_table=False),
                   steps=(replace(press, **kw),
                          replace(drag, bcs=drag_bcs, increments=20, **kw)))


def test_contact_zone_lost_in_one_increment_is_cut_back(shared_dir):
    """Coarse ironing, mu = 1, K = stick slope = 10 E/h, half a die element of drag per
    increment, plain Newton (the maps' ironing_stick_mu cell): diverging iterates threw the
    whole contact zone off the die, and two drag increments were accepted with no node in
    contact and no die force (LOST).  An increment that loses a whole contact zone by
    sliding off the master is now cut back; every drag increment keeps its contact."""
    result = run(_lost_zone_scene(shared_dir), write=False)
    assert result.summary.converged and result.summary.cutbacks > 0
    assert all(inc.active > 0 for inc in result.increments)


def test_warm_started_pairing_pairs_as_from_the_centroids(shared_dir, monkeypatch):
    """Pairing projects each candidate from its last projection point (interaction.py); in
    the lost-zone ironing run (fast sliding, nodes lost, cutbacks) every pairing takes the
    elements and lost nodes that projections from the face centroids give, xi to round-off."""
    import copy

    from dolfinx_friction.fem.pairing import ContactInteraction
    warm, pairings = ContactInteraction.pair, []

    def pair_twice(self, u, iteration):
        state = ("lost", "elements", "_first_pairing", "initial_gap", "_xi")
        saved = {k: copy.deepcopy(getattr(self, k)) for k in state}
        self._xi[:] = self.master.face.centroid
        warm(self, u, iteration)
        cold = (self.elements, self.lost)
        for k, v in saved.items():
            setattr(self, k, v)
        warm(self, u, iteration)
        for name in ("slave", "face", "candidate"):
            assert np.array_equal(getattr(self.elements, name), getattr(cold[0], name))
        assert np.array_equal(self.lost, cold[1])
        assert np.allclose(self.elements.xi, cold[0].xi, rtol=0.0, atol=1e-12)
        pairings.append(int(cold[1].sum()))

    monkeypatch.setattr(ContactInteraction, "pair", pair_twice)
    assert run(_lost_zone_scene(shared_dir), write=False).summary.converged
    assert len(pairings) > 100 and MPI.COMM_WORLD.allreduce(sum(pairings)) > 0  # nodes lost
