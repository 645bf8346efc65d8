"""demos/fenicsx_neo_hookean.py (the public API in a plain FEniCSx script) on 1, 2 and 3
ranks: in full slip the drag over the press force is mu = 0.3 (1e-8), every printed force
is the serial one (1e-8), and the XDMF time series is written.  The serial run compiles its
forms afresh (a new JIT cache) and prints nothing on stderr: the package does not print, and the
form compiler's chatter is silent.  demos/fenicsx_snes.py (the contact on a user's dolfinx
0.10+ NonlinearProblem) serially and on 2 ranks, or its one line on older releases.
Started from a serial pytest only (it launches its own ranks)."""
from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from tests.cli.test_cli import TIMEOUT, cli_env

pytestmark = [
    pytest.mark.skipif(MPI.COMM_WORLD.size > 1,
                       reason="launches mpirun itself: run from a serial pytest"),
    pytest.mark.skipif(shutil.which("mpirun") is None, reason="mpirun not found"),
]

DEMO = Path(__file__).resolve().parents[2] / "demos" / "fenicsx_neo_hookean.py"
LINE = re.compile(r"(press|slide) t = +([\d.]+) +Newton (\d+) +F_n = +(\S+) +F_t = +(\S+) +"
                  r"F_t/F_n = +(\S+)")


def _run(ranks: int, out: Path) -> np.ndarray:
    """(increments, 3): F_n, F_t and F_t/F_n printed for every increment."""
    from dolfinx_friction import _compat as compat
    command = [sys.executable, str(DEMO), "--cells", "12", "--no-picture", "--out", str(out)]
    env = cli_env()
    if ranks == 1:  # a fresh JIT cache: the forms and elements are compiled in this run
        env["XDG_CACHE_HOME"] = str(out / "jit-cache")
    if ranks > 1:
        command = [*compat.mpirun_command(ranks), *command]
        env = compat.mpirun_environment(env)
    proc = subprocess.run(command, capture_output=True, text=True, env=env, timeout=TIMEOUT)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    if ranks == 1:
        assert list((out / "jit-cache").rglob("*.so")), "nothing was compiled"
        assert proc.stderr == "", proc.stderr
    rows = [m.groups() for m in map(LINE.match, proc.stdout.splitlines()) if m]
    assert len(rows) == 15, proc.stdout
    assert (out / "block.xdmf").exists() and (out / "block.h5").exists()
    return np.array([[float(r[3]), float(r[4]), float(r[5])] for r in rows])


def test_demo_full_slip_ratio_and_ranks(tmp_path):
    serial = _run(1, tmp_path / "1")
    print(f"\nlast increment: F_n = {serial[-1, 0]:.10g}, F_t = {serial[-1, 1]:.10g}, "
          f"F_t/F_n = {serial[-1, 2]:.12f}")
    assert abs(serial[-1, 2] - 0.3) < 1e-8
    for ranks in (2, 3):
        forces = _run(ranks, tmp_path / str(ranks))
        scale = np.abs(serial[:, :2]).max()
        assert np.abs(forces[:, :2] - serial[:, :2]).max() < 1e-8 * scale, (ranks, forces)


SNES_DEMO = DEMO.with_name("fenicsx_snes.py")
SNES_LINE = re.compile(r"(press|slide) t = ([\d.]+) +SNES +(\d+) +F_n = (\S+) +F_t = (\S+) +"
                       r"F_t/F_n = (\S+) +contact (\d+), slip (\d+)")


def _run_snes_demo(ranks: int) -> subprocess.CompletedProcess:
    from dolfinx_friction import _compat as compat
    command, env = [sys.executable, str(SNES_DEMO)], cli_env()
    if ranks > 1:
        command = [*compat.mpirun_command(ranks), *command]
        env = compat.mpirun_environment(env)
    proc = subprocess.run(command, capture_output=True, text=True, env=env, timeout=TIMEOUT,
                          check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc


def test_snes_demo_full_slip_ratio_and_ranks():
    """demos/fenicsx_snes.py: on dolfinx 0.10+ every increment converges (the log of
    increments is the script's own history), full slip gives F_t/F_n = mu = 0.3 (1e-8)
    and 2 ranks print the serial forces (1e-8); older releases get one line and exit 0."""
    from tests.fem.test_snes_idiom import SNES_PROBLEM
    if not SNES_PROBLEM:
        lines = _run_snes_demo(1).stdout.splitlines()
        assert len(lines) == 1 and "needs dolfinx >= 0.10" in lines[0], lines
        return
    runs = []
    for ranks in (1, 2):
        out = _run_snes_demo(ranks).stdout
        rows = np.array([[float(v) for v in m.groups()[1:]]
                         for m in map(SNES_LINE.match, out.splitlines()) if m])
        assert f"{len(rows)} increments, " in out and rows[-1, 0] == 2.0, out
        runs.append(rows)
    serial = runs[0]
    assert abs(serial[-1, 4] - 0.3) < 1e-8 and serial[-1, 6] == serial[-1, 5] > 0
    scale = np.abs(serial[:, 2:4]).max()
    assert runs[1].shape == serial.shape
    assert np.abs(runs[1][:, 2:4] - serial[:, 2:4]).max() < 1e-8 * scale
