"""Checks of a scene built in Python or read from TOML (masses, inertia, names, layout).

Every problem raises :class:`labkit.sim.scene.SceneError` naming the file, the key and the reason.
"""

from __future__ import annotations

import numpy as np

from labkit.sim.scene import Scene, SceneError


def validate_scene(scene: Scene) -> None:
    """Check a scene built in Python or read from TOML; raise :class:`SceneError` if wrong."""
    validate_bodies(scene)
    validate_layout(scene)


def validate_bodies(scene: Scene) -> None:
    """Masses, inertia tensors, damping and names."""
    src = scene.source
    if not scene.bodies:
        raise SceneError(src, "body", "a scene needs at least one body")
    names = [b.name for b in scene.bodies] + [r.name for r in scene.rotators]
    if len(set(names)) != len(names):
        raise SceneError(src, "body.name", f"names must be unique, got {names}")
    for i, b in enumerate(scene.bodies):
        key = f"body[{i}]"
        if not (b.mass_kg > 0):
            raise SceneError(src, f"{key}.mass_kg", f"mass must be positive, got {b.mass_kg!r}")
        inertia = np.asarray(b.inertia_kg_m2, dtype=float)
        if inertia.shape != (3, 3) or not np.allclose(inertia, inertia.T, rtol=1e-12, atol=0.0):
            raise SceneError(src, f"{key}.inertia_kg_m2", "inertia tensor must be a symmetric 3x3 matrix")
        eig = np.linalg.eigvalsh(inertia)
        if eig[0] <= 0:
            raise SceneError(
                src,
                f"{key}.inertia_kg_m2",
                f"inertia tensor is not positive definite (eigenvalues {eig.tolist()})",
            )
        if eig[0] + eig[1] < eig[2] * (1.0 - 1e-9):
            raise SceneError(
                src,
                f"{key}.inertia_kg_m2",
                f"principal moments {eig.tolist()} violate I1 + I2 >= I3 (no rigid body has them)",
            )
        for attr in ("damping_N_s_m", "damping_rot_N_m_s"):
            if getattr(b, attr) < 0:
                raise SceneError(src, f"{key}.{attr}", "damping must not be negative")
    if scene.escape_radius_m is not None and scene.escape_radius_m <= 0:
        raise SceneError(src, "scene.escape_radius_m", "must be positive")


def validate_layout(scene: Scene) -> None:
    """Overlapping bodies and rotators (bounding spheres at t = 0)."""
    src = scene.source
    spheres = [
        (f"body[{i}]", b.name, b.position_m, b.shape.contact_radius_m) for i, b in enumerate(scene.bodies)
    ]
    for j, r in enumerate(scene.rotators):
        spheres.append((f"rotator[{j}]", r.name, r.axis_point_m, r.contact_radius_m))
    for a in range(len(spheres)):
        for c in range(a + 1, len(spheres)):
            ka, na, pa, ra = spheres[a]
            kc, nc, pc, rc = spheres[c]
            d = float(np.linalg.norm(np.asarray(pa) - np.asarray(pc)))
            if d < ra + rc or (d == 0.0):
                raise SceneError(
                    src,
                    f"{kc}.initial.position_m" if kc.startswith("body") else f"{kc}.axis_point_m",
                    f"{nc} overlaps {na} ({ka}): centres {d * 1e3:.3g} mm apart, "
                    f"contact radii sum {(ra + rc) * 1e3:.3g} mm",
                )
