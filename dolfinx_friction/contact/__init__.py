"""The contact element, batched over pairs: projection, pressure–overclosure laws, radial
return and the exact tangent (docs/theory.md).  numpy reference and numba kernels; imports
no dolfinx."""
from dolfinx_friction._lazy import lazy_names

_PUBLIC = {
    "Linear": "laws", "Exponential": "laws", "Tabular": "laws",
    "ContactParameters": "element", "ElementResult": "element", "evaluate": "element",
    "FrictionState": "friction", "FACE_TYPES": "shapes", "FaceType": "shapes",
    "project": "projection", "clearances": "projection",
}
__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
