"""Files: Gmsh meshes (split into bodies, cached, as dolfinx meshes), input-file checks,
atomic writes, the result writers (history.csv, contact.csv, summary.json, XDMF fields and
their time series) and readers."""
from dolfinx_friction._lazy import lazy_names

_PUBLIC = {
    "load_mesh": "gmsh", "MeshError": "msh", "BodyMesh": "gmsh", "MeshSet": "gmsh",
    "read_split": "msh", "MeshSplit": "msh",
    "file_fault": "files", "ResultWriter": "writer", "FieldWriter": "writer",
    "read_run": "reader", "read_csv": "reader", "RunFiles": "reader", "ResultsError": "reader",
    "write_atomic": "files", "atomic_path": "files",
}
__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
