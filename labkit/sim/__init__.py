"""labkit.sim: scenes, compiling a scene to what it needs, integrators, invariants.

Public interface::

    from labkit.sim import load_scene, compile_scene, simulate
    result = simulate("conical_5_1", cycles=100)          # bundled scene, default splitting4
    result.status, result.invariant_drift, result.qoi

``labkit.sim`` never prints and never imports a viewer; streaming sinks read
``SimResult.poses()``.
"""

from labkit.sim.compile import CompiledSystem, compile_scene
from labkit.sim.integrators import DEFAULT_INTEGRATOR, INTEGRATORS, SimulationError
from labkit.sim.result import SimResult
from labkit.sim.run import simulate
from labkit.sim.scene import (
    Body,
    Rotator,
    Scene,
    SceneError,
    Shape,
    UniformField,
    bundled_scenes,
    load_scene,
    scene_from_dict,
    validate_scene,
)

__all__ = [
    "Body",
    "CompiledSystem",
    "DEFAULT_INTEGRATOR",
    "INTEGRATORS",
    "Rotator",
    "Scene",
    "SceneError",
    "Shape",
    "SimResult",
    "SimulationError",
    "UniformField",
    "bundled_scenes",
    "compile_scene",
    "load_scene",
    "scene_from_dict",
    "simulate",
    "validate_scene",
]
