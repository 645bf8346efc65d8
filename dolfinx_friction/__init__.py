"""Node-to-surface penalty contact with Coulomb friction for DOLFINx."""
__version__ = "0.1.0"
