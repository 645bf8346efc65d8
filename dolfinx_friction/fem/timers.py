"""Wall-clock and CPU time per phase of a solve (set-up, search, assemblies, solve, output)."""
from __future__ import annotations

import contextlib
import time
from dataclasses import dataclass, field

__all__ = ["PHASES", "Timers"]

PHASES = ("setup", "contact_search", "contact_assembly", "bulk_assembly", "linear_solve",
          "output")


@dataclass
class Timers:
    """Time per phase, seconds: ``phases`` wall clock, ``cpu`` this process's CPU time
    (on a shared machine the wall clock also counts the other jobs)."""

    phases: dict = field(default_factory=lambda: dict.fromkeys(PHASES, 0.0))
    cpu: dict = field(default_factory=lambda: dict.fromkeys(PHASES, 0.0))

    def add(self, phase: str, seconds: float, cpu: float = 0.0) -> None:
        self.phases[phase] += seconds
        self.cpu[phase] += cpu

    @contextlib.contextmanager
    def measure(self, phase: str):
        """Add the wall and CPU time of the ``with`` block to ``phase``."""
        wall, cpu = time.perf_counter(), time.process_time()
        try:
            yield
        finally:
            self.add(phase, time.perf_counter() - wall, time.process_time() - cpu)
