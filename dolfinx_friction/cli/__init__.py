"""The command line ``dolfinx-friction run|check|sweep|plot|render``: one front end, its
exit codes, signals and progress display."""
from dolfinx_friction._lazy import lazy_names

_PUBLIC = {
    "main": "frontend", "Progress": "progress", "run_sweep": "sweep",
}
__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
