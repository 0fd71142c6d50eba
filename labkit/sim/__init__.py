"""labkit.sim: scenes, compiling a scene to what it needs, integrators, invariants.

Public interface::

    from labkit.sim import load_scene, compile_scene, simulate
    result = simulate("conical_5_1", cycles=100)          # bundled scene, default splitting4
    result.status, result.invariant_drift, result.qoi

``labkit.sim`` never prints and never imports a viewer; streaming sinks read
``SimResult.poses()``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from labkit.lazy import lazy_attributes

#: where each public name lives; imported on first use (PEP 562) so that ``labkit --help``
#: and ``import labkit.sim.scene`` do not pay for numba and scipy.
_HOME = {
    "CompiledSystem": "labkit.sim.compile",
    "compile_scene": "labkit.sim.compile",
    "DEFAULT_INTEGRATOR": "labkit.sim.integrators",
    "INTEGRATORS": "labkit.sim.integrators",
    "SimulationError": "labkit.sim.integrators.raw_run",
    "SimResult": "labkit.sim.result",
    "simulate": "labkit.sim.run",
    **{name: "labkit.sim.scene" for name in (
        "Body", "Rotator", "Scene", "SceneBody", "SceneError", "Shape", "UniformField")},
    **{name: "labkit.sim.scene_file" for name in ("bundled_scenes", "load_scene", "scene_from_dict")},
    "validate_scene": "labkit.sim.scene_checks",
}

if TYPE_CHECKING:  # pragma: no cover
    from labkit.sim.compile import CompiledSystem, compile_scene
    from labkit.sim.integrators import DEFAULT_INTEGRATOR, INTEGRATORS
    from labkit.sim.integrators.raw_run import SimulationError
    from labkit.sim.result import SimResult
    from labkit.sim.run import simulate
    from labkit.sim.scene import (
        Body,
        Rotator,
        Scene,
        SceneBody,
        SceneError,
        Shape,
        UniformField,
    )
    from labkit.sim.scene_checks import validate_scene
    from labkit.sim.scene_file import bundled_scenes, load_scene, scene_from_dict


__getattr__ = lazy_attributes(__name__, _HOME)


__all__ = [
    "Body",
    "CompiledSystem",
    "DEFAULT_INTEGRATOR",
    "INTEGRATORS",
    "Rotator",
    "Scene",
    "SceneBody",
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
