"""The FEniCSx building block: contact surfaces from a space and facet tags, rigid
obstacles (obstacles), a contact's settings and defaults (contact_settings), a body's mesh
with named groups (tagged_mesh), search and pairing, :class:`NodeToSurface` (one contact
pair), the matrix pattern with the contact couplings, :class:`BlockProblem` (bodies given
by UFL residuals, coupled by contact), contact states as arrays (contact_fields), elastic
constants (materials) and the UFL of axisymmetric bodies (axisymmetric).  Imports dolfinx,
PETSc, the contact core and the stdlib-only rules and errors; nothing of the scene, io,
viz, cli or reference layers."""
from dolfinx_friction._lazy import lazy_names

_PUBLIC = {
    "NodeToSurface": "node_to_surface", "Surface": "node_to_surface",
    "ContactState": "node_to_surface", "ContactSetupError": "node_to_surface",
    "NO_ELEMENT": "node_to_surface", "rigid_plane": "obstacles",
    "rigid_sphere": "obstacles", "rigid_cylinder": "obstacles", "Obstacle": "obstacles",
    "rigid_sdf": "obstacles", "SignedDistance": "obstacles",
    "ContactSettings": "contact_settings", "BodyMesh": "tagged_mesh",
    "create_matrix": "node_to_surface", "BlockProblem": "block_problem", "Timers": "block_problem",
    "CooPattern": "pattern", "DofLayout": "numbering", "SlaveNodes": "surfaces",
    "MasterFaces": "surfaces", "ContactInteraction": "pairing", "lame": "materials",
    "bulk_modulus": "materials", "out_of_plane": "materials", "nodal_fields": "contact_fields",
    "slave_rows": "contact_fields", "add_contact": "snes", "SNESContact": "snes",
    "axisymmetric_grad": "axisymmetric", "revolution_weight": "axisymmetric",
}
__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
