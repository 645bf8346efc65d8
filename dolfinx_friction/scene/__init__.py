"""Scenes: the model (dataclasses), its validation (the one place for the rules), TOML
reading, building a problem from a scene, the step driver, :func:`run` with its callbacks
(:class:`RunControl`) and provenance.  The model, validation and reading import no
dolfinx."""
from dolfinx_friction._lazy import lazy_names

_PUBLIC = {
    "Scene": "model", "Body": "model", "Rigid": "model", "ContactPair": "model", "BC": "model",
    "Load": "model", "RigidMotion": "model", "Step": "model", "Output": "model",
    "SolverSettings": "model",
    "SceneError": "validation", "ModelError": "validation", "load_scene": "toml",
    "parse_scene": "toml", "apply_override": "toml", "default_output_dir": "toml",
    "DiscreteScene": "build", "ContactProblem": "build", "Solver": "driver",
    "Increment": "driver", "RunSummary": "driver", "run": "runner", "RunResult": "runner",
    "RunControl": "control",
}
__all__ = sorted(_PUBLIC)
__getattr__, __dir__ = lazy_names(__name__, _PUBLIC)
