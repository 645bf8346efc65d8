"""References to verify against: closed-form solutions (Hertz, Cattaneo–Mindlin, ...),
the CalculiX deck writer and runner, the comparisons of contact results, and the meshes
(meshes) and CalculiX comparison scenes (cases) that the tests and benchmarks share."""
from dolfinx_friction._lazy import lazy_names

_PUBLIC = {
    "hertz_line": "analytic", "hertz_sphere": "analytic", "write_inp": "calculix",
    "run_ccx": "calculix", "ccx_available": "calculix", "contact_state": "compare",
}
__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
