"""The command line ``dolfinx-friction run|check|sweep|plot|render``: one front end
(frontend), the commands' bodies (commands), exit statuses (exits), signals, the MPI
launcher (mpi), the progress display and sweeps.  Nothing in the library imports it."""
from dolfinx_friction._lazy import lazy_names

_PUBLIC = {
    "main": "frontend", "Progress": "progress", "run_sweep": "sweep",
    "Interruption": "signals",
}
__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
