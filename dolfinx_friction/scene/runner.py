"""Run a scene: the entry point shared by the command line and Python scripts."""
from __future__ import annotations

import logging
import resource
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional, Sequence, Union

from mpi4py import MPI

from dolfinx_friction.io.gmsh import MeshSet
from dolfinx_friction.nls.defaults import ITERATIVE, choose
from dolfinx_friction.nls.linear import release_garbage
from dolfinx_friction.scene.model import Scene
from dolfinx_friction.io.writer import ResultWriter
from dolfinx_friction.scene.build import ContactProblem
from dolfinx_friction.scene.control import RunControl, checkpoint
from dolfinx_friction.scene.provenance import provenance
from dolfinx_friction.scene.toml import SceneError, default_output_dir, load_scene
from dolfinx_friction.scene.driver import ConvergenceError, Increment, RunSummary, Solver
from dolfinx_friction.scene.workspace import Workspace


log = logging.getLogger(__name__)

#: Overclosure, as a share of the slave node spacing, beyond which a run warns that the
#: penalty is too soft for the mesh.
PENETRATION_WARNING = 0.05
#: Chord depth of quadratic slave faces on first-order geometry, as a share of the largest
#: overclosure, beyond which a run warns: the vertex nodes' pressures err by about as much.
FACETING_WARNING = 0.02


@dataclass
class RunResult:
    """What a run produced: the solved problem, its increments and where the files are."""

    problem: ContactProblem
    summary: RunSummary
    increments: list[Increment]
    directory: Optional[Path]
    #: the solver that ran it (its Newton system, linear solver and timers), for inspection
    solver: Optional[Solver] = None


def peak_memory_mib() -> float:
    """This process's peak resident memory so far [MiB] (Linux: ``ru_maxrss`` in KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def linear_solver(problem: ContactProblem, petsc_options: Optional[dict],
                  reuse: Optional[bool]) -> tuple[Optional[dict], Optional[bool]]:
    """The linear solver's options and ``reuse_factorisation`` for ``problem``: those given
    to :func:`run`, else the scene's ``[solver]`` (``"auto"`` chooses by the number of
    unknowns, :func:`~dolfinx_friction.nls.defaults.choose`); None: MUMPS, as the solver
    decides."""
    settings = problem.scene.solver
    if reuse is None:
        reuse = settings.reuse_factorisation
    if petsc_options is not None:
        return petsc_options, reuse
    kind = choose(settings.linear, problem.system.x.getSize(), problem.gdim,
                  settings.direct_max_dofs)
    options = {**(ITERATIVE if kind == "iterative" else {}), **dict(settings.petsc_options)}
    return options or None, reuse


def _release(solver: Solver, workspace: Optional[Workspace]) -> None:
    """The end of a run (collective): the solver's factorisations and the PETSc objects
    dropped on the communicators of its meshes (:meth:`Solver.release`) and of the other
    meshes ``workspace`` keeps (those of the run before, dropped since) are freed."""
    solver.release()
    if workspace is not None:
        release_garbage(body.mesh.comm for meshes in workspace.values()
                        if isinstance(meshes, MeshSet) and meshes is not solver.problem.meshes
                        for body in meshes.bodies.values())


def run(scene: Union[Scene, str, Path], out: Union[str, Path, None] = None,
        overrides: Sequence[str] = (), write: bool = True,
        comm: MPI.Comm = MPI.COMM_WORLD, petsc_options: Optional[dict] = None,
        reuse_factorisation: Optional[bool] = None,
        progress: Optional[Callable[[Increment], None]] = None,
        control: Optional[RunControl] = None,
        workspace: Optional[Workspace] = None,
        max_increments: Optional[int] = None) -> RunResult:
    """Solve a scene (a :class:`Scene` or a scene file) and write its results.

    ``overrides`` (``KEY=VALUE`` as ``--set`` takes them) apply to a scene file only (a
    :class:`Scene` is changed with ``dataclasses.replace``); ``out`` overrides
    ``[output] dir``; ``write=False`` keeps everything in memory;
    ``progress`` is called with every converged increment once it is written (e.g. a
    :class:`~dolfinx_friction.cli.progress.Progress`; on every rank where it is given);
    ``control`` (:mod:`~dolfinx_friction.scene.control`, on every rank) follows the run
    and may stop it at a checkpoint (:class:`~dolfinx_friction.errors.Interrupted`);
    ``workspace`` (:mod:`~dolfinx_friction.scene.workspace`) keeps the meshes, spaces and
    compiled forms for the next run given it, and gives this one what the last one kept
    (the same results, bit for bit); ``max_increments`` stops the run after that many
    converged increments (written as any; ``summary.converged`` stays False).
    Nothing is printed: warnings (a penalty too soft for the mesh, nodes that slid off
    their master) and notices go to the ``dolfinx_friction`` logger, from rank 0;
    ``petsc_options`` (without prefix) set the linear solver; ``reuse_factorisation``
    keeps a factorisation as GMRES preconditioner across Newton iterations (default:
    yes with the default MUMPS solver, no with ``petsc_options``; see ``linear``).
    Raises :class:`ConvergenceError` (after writing ``summary.json``) when an
    increment fails after all cutbacks.
    """
    start, cpu = time.perf_counter(), time.process_time()
    if not isinstance(scene, Scene):
        scene = load_scene(Path(scene), list(overrides))
    elif overrides:
        raise SceneError("overrides apply to a scene file; change a Scene object with "
                         "dataclasses.replace", key="overrides")
    if workspace is not None:
        workspace.start()
    problem = ContactProblem(scene, comm, workspace=workspace)
    petsc_options, reuse_factorisation = linear_solver(problem, petsc_options,
                                                       reuse_factorisation)
    solver = Solver(problem, petsc_options=petsc_options,
                    reuse_factorisation=reuse_factorisation)
    directory = Path(out) if out is not None else (scene.output.dir or default_output_dir(scene))
    writer = None
    if write:
        writer = ResultWriter(problem, solver.reaction_groups(), directory, scene.output.fields,
                              scene.output.contact_table)
    if control is not None:
        control.begin(directory if write else None)
    solver.timers.add("setup", time.perf_counter() - start, time.process_time() - cpu)
    increments: list[Increment] = []
    warnings: dict[str, str] = {}

    def warn(key: str, text: str) -> None:
        if key not in warnings:
            warnings[key] = text
            if comm.rank == 0:
                log.warning(text)

    def record(inc: Increment) -> None:
        # an increment that converges after the control was told to stop is not kept
        checkpoint(control, comm)
        increments.append(inc)
        for pair, ratio in inc.penetration.items():
            if ratio > PENETRATION_WARNING:
                warn(pair, f"contact {pair}: overclosure reaches {ratio:.1%} of the slave node "
                           f"spacing at t = {inc.t:.4g}; the penalty K is too soft for this mesh")
        for name, pair in problem.pairs.items():
            depth, ratio = pair.faceting()
            if ratio > FACETING_WARNING:
                warn(name + " faceted", f"contact {name}: quadratic slave faces on first-order "
                     f"geometry: mid-side nodes {depth:.2g} inside the curved surface, "
                     f"{ratio:.0%} of the overclosure, so the nodal pressures err by about as "
                     f"much; mesh it with second-order geometry (gmsh Mesh.ElementOrder = 2)")
        for pair, count in inc.detached.items():
            if count:
                warn(pair + " detached", f"contact {pair}: {count} slave node(s) in contact slid "
                                         f"off the master surface at t = {inc.t:.4g}")
        if writer is not None:
            # a stop asked from now on comes after this increment, which is written whole
            # first: the run works on the next one (of the next step at t = 1)
            if control is not None:
                control.attempt(*((inc.step + 1, 1) if inc.t - inc.step > 1.0 - 1e-12
                                  else (inc.step, inc.increment + 1)))
            with solver.timers.measure("output"):
                writer.increment(inc)
            checkpoint(control, comm)  # every rank stops here, all together
        if progress is not None:
            progress(inc)

    def extra() -> dict:  # summary.json beyond the counts: what was run, and the warnings
        peak = comm.allreduce(peak_memory_mib(), op=MPI.MAX)
        if comm.rank != 0:
            return {}
        return {**provenance(problem, solver.reaction_groups(), solver.linear),
                "linear_solves": solver.summary.linear_solves,
                "peak_memory_mib": peak, "warnings": list(warnings.values())}

    try:
        summary = solver.run(record, control, max_increments)
    except ConvergenceError:
        solver.summary.wall = time.perf_counter() - start
        if writer is not None:
            writer.summary(solver.summary, extra())
        _release(solver, workspace)
        raise
    summary.wall = time.perf_counter() - start
    if writer is not None:
        writer.summary(summary, extra())
    _release(solver, workspace)
    return RunResult(problem, summary, increments, directory if write else None, solver)
