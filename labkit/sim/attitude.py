"""What a run stores of each body's attitude (docs/decisions/0015-store-what-the-scene-needs.md).

An axisymmetric body (inertia ``a 1 + b u u^T``, dipole moment and dipole offset along ``u``) is
described by its axis ``u`` in the lab and its angular momentum: the turn about ``u`` changes
neither its energy nor any force or torque on it (docs/reference/simulator.md, *Long runs*). A run keeps
that unit vector (3 floats per sample) for such a body and the full rotation matrix (9 floats)
for any other body, or for every body when asked (``attitude="matrix"``).

Every body has an *axis*, a unit vector fixed in the body: its dipole direction; without a
dipole, the symmetry axis of an axisymmetric body, else body z. ``SimResult.axes`` holds its lab
direction for every body and every sample.
"""

from __future__ import annotations

import numpy as np

ATTITUDES = ("axis", "matrix")
_TOLERANCE = 1e-9  # relative, as labkit.sim.compile's test for equal principal moments


def body_axis(inertia: np.ndarray, moment: np.ndarray, offset: np.ndarray) -> tuple[np.ndarray, bool]:
    """``(axis, axisymmetric)``: the body's unit axis in its own frame (see the module docstring)
    and whether the body is axisymmetric about it."""
    inertia, moment, offset = (np.asarray(a, dtype=float) for a in (inertia, moment, offset))
    if np.linalg.norm(moment) > 0:
        axis = moment / np.linalg.norm(moment)
    else:
        axis = _symmetry_axis(inertia)
        if axis is None:
            return np.array([0.0, 0.0, 1.0]), False
    return axis, _symmetric_about(inertia, axis) and _parallel(offset, axis)


def _symmetry_axis(inertia: np.ndarray) -> np.ndarray | None:
    """The unique principal axis of a symmetric top, body z for an isotropic body, else None."""
    eig, vec = np.linalg.eigh(inertia)
    scale = max(abs(eig[-1]), 1e-300)
    if abs(eig[2] - eig[0]) <= _TOLERANCE * scale:
        return np.array([0.0, 0.0, 1.0])
    if abs(eig[1] - eig[0]) <= _TOLERANCE * scale:
        return vec[:, 2]
    if abs(eig[2] - eig[1]) <= _TOLERANCE * scale:
        return vec[:, 0]
    return None


def _symmetric_about(inertia: np.ndarray, u: np.ndarray) -> bool:
    """Whether ``inertia == a 1 + b u u^T`` (to the relative tolerance)."""
    along = float(u @ inertia @ u)
    across = 0.5 * (np.trace(inertia) - along)
    model = across * np.eye(3) + (along - across) * np.outer(u, u)
    return bool(np.linalg.norm(inertia - model) <= _TOLERANCE * max(np.linalg.norm(inertia), 1e-300))


def _parallel(v: np.ndarray, u: np.ndarray) -> bool:
    return bool(np.linalg.norm(np.cross(v, u)) <= _TOLERANCE * max(np.linalg.norm(v), 1e-300))


def _near_turns(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rodrigues' shortest turns from ``a`` to each ``b`` with ``b . a >= 0`` (well conditioned:
    ``1 + cos`` stays >= 1)."""
    k = np.cross(a, b)  # sin(angle) * unit rotation axis
    c = b @ a  # cos(angle)
    kx = np.zeros(b.shape[:-1] + (3, 3))
    kx[..., 0, 1], kx[..., 0, 2], kx[..., 1, 2] = -k[..., 2], k[..., 1], -k[..., 0]
    kx[..., 1, 0], kx[..., 2, 0], kx[..., 2, 1] = k[..., 2], -k[..., 1], k[..., 0]
    return np.eye(3) + kx + (kx @ kx) / (1.0 + c)[..., None, None]


def shortest_turns(axis_body: np.ndarray, axes_lab: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotations taking the body-frame vector ``axis_body`` to each of ``axes_lab``
    (n, 3) by the shortest turn (Rodrigues); a half turn is about a fixed perpendicular. For
    drawing an axisymmetric body, which looks the same after any turn about its axis.

    A target more than a quarter turn away is reached as a half turn about that perpendicular
    followed by the short turn from ``-axis_body``: Rodrigues' ``1 / (1 + cos)`` would lose all
    precision for nearly opposite vectors."""
    a = np.asarray(axis_body, dtype=float)
    b = np.asarray(axes_lab, dtype=float)
    far = (b @ a) < 0.0
    out = np.empty(b.shape[:-1] + (3, 3))
    out[~far] = _near_turns(a, b[~far])
    if np.any(far):
        p = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
        p /= np.linalg.norm(p)
        half = 2.0 * np.outer(p, p) - np.eye(3)  # half turn about p: a -> -a
        out[far] = _near_turns(-a, b[far]) @ half
    return out
