"""Pictures and charts: :func:`render` (pyvista, off screen) of a live problem or of
written results, and matplotlib charts of histories and sweeps.  Import pyvista (this
layer) before dolfinx in a process that renders."""
from dolfinx_friction._lazy import lazy_names

_PUBLIC = {
    "render": "pictures", "draw": "pictures", "render_files": "snapshot",
    "plot_history": "plots", "plot_sweep": "plots",
}
__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
