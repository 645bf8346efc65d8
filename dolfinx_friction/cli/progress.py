"""What a run shows while it solves: on a terminal a progress bar per step (tqdm), else one
line per converged increment.

A :class:`Progress` is the ``progress`` callback of :func:`dolfinx_friction.scene.runner.run`: it is
called with every converged, written increment.  Give it on one rank only (the command
line gives it on rank 0).  Nothing here imports dolfinx.
"""
from __future__ import annotations

import sys
import time
from typing import TYPE_CHECKING, Optional, TextIO

if TYPE_CHECKING:
    from dolfinx_friction.scene.driver import Increment

#: The bar of a step: its pseudo-time from 0 to 1, the last increment, the time left.
BAR_FORMAT = "{desc}: {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}{postfix}]"


def increment_line(inc: "Increment") -> str:
    """One line on a converged increment (the progress of a run outside a terminal)."""
    return (f"step {inc.step} ({inc.step_name}) increment {inc.increment}: "
            f"t = {inc.t:.4f}, {inc.iterations} Newton iterations, residual "
            f"{inc.residual:.2e}, {inc.active} in contact, {inc.slipping} slipping")


class Progress:
    """A progress bar per step when ``stream`` is a terminal, else :func:`increment_line`
    per increment; :meth:`close` after the run (also when it failed)."""

    def __init__(self, stream: Optional[TextIO] = None):
        self.stream = stream if stream is not None else sys.stdout
        self.bar_mode = self.stream.isatty()
        self._bar = None
        self._step: Optional[int] = None

    def __call__(self, inc: "Increment") -> None:
        if not self.bar_mode:
            print(increment_line(inc), file=self.stream, flush=True)
            return
        if inc.step != self._step:
            self._open(inc)
        bar = self._bar
        bar.set_postfix_str(f"increment {inc.increment}, t = {inc.t:.4f}, "
                            f"{inc.iterations} Newton iterations", refresh=False)
        bar.n = min(max(inc.t - inc.step, 0.0), 1.0)  # the share of the step done
        bar.refresh()

    def _open(self, inc: "Increment") -> None:
        from tqdm import tqdm
        self.close()
        self._step = inc.step
        self._bar = tqdm(total=1.0, desc=f"step {inc.step} ({inc.step_name})",
                         bar_format=BAR_FORMAT, file=self.stream, smoothing=0.0,
                         dynamic_ncols=True, leave=True)
        # the time left: the step's mean rate so far, from when its first increment began
        self._bar.start_t = self._bar.last_print_t = time.time() - inc.wall

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
