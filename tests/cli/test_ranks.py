"""Every demo scene (the analytic verification scenes among them) on 1, 2 and 3 ranks.

Each scene runs through the command line serially and under ``mpirun -n 2`` and
``mpirun -n 3`` (oversubscribed on a 2-core machine), with the direct solver; the
reactions and rigid-obstacle translations and forces of every increment must equal the
serial ones to 1e-8 relative, and the same slave nodes must be in contact with the same
status.  Started from a serial pytest only (the subprocesses launch their own ranks).
"""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from mpi4py import MPI

from tests.cli.test_cli import assert_same_history, cli, mpirun_cli, read_csv

pytestmark = [
    pytest.mark.skipif(MPI.COMM_WORLD.size > 1,
                       reason="launches mpirun itself: run from a serial pytest"),
    pytest.mark.skipif(shutil.which("mpirun") is None, reason="mpirun not found"),
]

DEMOS = Path(__file__).resolve().parents[2] / "demos"
SCENES = sorted(p.stem for p in DEMOS.glob("*.toml"))


def _run(scene: str, ranks: int, out: Path):
    args = ("run", DEMOS / f"{scene}.toml", "--out", out, "--quiet",
            "--set", "output.fields=false")
    outcome = cli(*args) if ranks == 1 else mpirun_cli(ranks, *args)
    assert outcome.status == 0 and outcome.stderr == "", str(outcome)
    return read_csv(out / "history.csv")[1], read_csv(out / "contact.csv")[1]


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    root = tmp_path_factory.mktemp("serial")
    cache: dict[str, tuple] = {}

    def get(scene: str):
        if scene not in cache:
            cache[scene] = _run(scene, 1, root / scene)
        return cache[scene]
    return get


def test_every_demo_has_its_mesh():
    import tomllib
    assert len(SCENES) >= 8
    for scene in SCENES:
        mesh = tomllib.loads((DEMOS / f"{scene}.toml").read_text())["mesh"]["file"]
        assert (DEMOS / mesh).exists(), scene


@pytest.mark.parametrize("ranks", [2, 3])
@pytest.mark.parametrize("scene", SCENES)
def test_ranks_match_serial(scene, ranks, serial, tmp_path):
    history, contact = _run(scene, ranks, tmp_path / scene)
    serial_history, serial_contact = serial(scene)
    assert_same_history(history, serial_history)
    assert [(r["step"], r["increment"], r["node"], r["status"]) for r in contact] == \
        [(r["step"], r["increment"], r["node"], r["status"]) for r in serial_contact]
