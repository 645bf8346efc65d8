"""The FEniCSx building block: contact surfaces from a space and facet tags, rigid
obstacles, search and pairing, :class:`NodeToSurface` (one contact pair), the matrix pattern
with the contact couplings, :class:`BlockProblem` (bodies given by UFL residuals, coupled by
contact), contact states as arrays (contact_fields) and elastic constants (materials).  Imports dolfinx, PETSc and the contact core; nothing of the scene, io, viz or
cli layers."""
from dolfinx_friction._lazy import lazy_names

_PUBLIC = {
    "NodeToSurface": "node_to_surface", "Surface": "node_to_surface",
    "ContactState": "node_to_surface", "ContactSetupError": "node_to_surface",
    "NO_ELEMENT": "node_to_surface", "rigid_plane": "node_to_surface",
    "rigid_sphere": "node_to_surface", "rigid_cylinder": "node_to_surface",
    "create_matrix": "node_to_surface", "BlockProblem": "block_problem", "Timers": "block_problem",
    "CooPattern": "pattern", "DofLayout": "numbering", "SlaveNodes": "surfaces",
    "MasterFaces": "surfaces", "ContactInteraction": "pairing", "lame": "materials",
    "bulk_modulus": "materials", "out_of_plane": "materials", "nodal_fields": "contact_fields",
    "slave_rows": "contact_fields",
}
__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
