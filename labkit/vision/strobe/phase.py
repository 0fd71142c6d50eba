"""Phase models of stroboscope footage (docs/explanation/strobe-analysis.md, *Phase models*).

The rotor turns at ``f_rot``; what a frame shows is the body at the rotor phase of the light that
exposed it. With flash times ``t_j = t_0 + j / f_s`` the phase of flash j is
``2 pi f_rot t_j = 2 pi (f_rot / f_s) j + c``: only the alias matters,

    f_a = f_rot - m f_s,   m = round(f_rot / f_s)  (the strobe harmonic),

and the body seen at time t moves at the apparent frequency ``f_a`` in real time. A camera at
``F`` frames per second integrates the flashes within its exposure ``T_e``; their mean time is
``k / F + T_e / 2`` (+- ``1 / (2 f_s)`` with several flashes), so frame k shows

    psi_k = 2 pi f_a k / F + const,     i.e.  c = f_a / F cycles per frame.        (P1)

One flash per frame (``f_s = F``) is the special case ``c = f_rot / f_s - m``. Without a lamp the
camera's short exposure is the strobe (Fig. 6.20): ``f_s = F`` in (P1). The motion during one
exposure is ``f_a T_e`` cycles with a lamp (``f_rot T_e`` without); it averages the body over that
phase span and shrinks amplitudes by ``sinc = sin(pi u) / (pi u)``, u the cycles per exposure.
Frequencies in the file header may lie (slow-motion files): ``camera_fps`` overrides ``F``.

From the signal alone, ``c`` is the frequency that best explains tilt and lateral position as
sinusoids; its sign (the sense of the apparent rotation) and ``c`` versus ``1 - c`` cannot be told
apart, and neither changes the amplitudes.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np


@dataclass(frozen=True)
class PhaseModel:
    """How frame index maps to rotor phase: ``psi_k = 2 pi cycles_per_frame k`` (P1)."""

    kind: str  # "lamp", "camera", "apparent" or "signal"
    cycles_per_frame: float
    camera_fps: float | None
    apparent_hz: float | None
    harmonic_m: int | None = None
    flashes_per_frame: float | None = None
    cycles_per_exposure: float | None = None  # motion within one exposure (blur), when known
    equation: str = ""
    source: str = ""

    def phases(self, frames: np.ndarray) -> np.ndarray:
        return 2 * math.pi * self.cycles_per_frame * np.asarray(frames, float)

    @property
    def blur_factor(self) -> float:
        """Amplitude kept by averaging over one exposure, sinc(u); 1 when the exposure is unknown."""
        u = self.cycles_per_exposure
        if not u:
            return 1.0
        return math.sin(math.pi * u) / (math.pi * u)

    def to_json(self) -> dict:
        """The result's ``phase_model`` object: the fields and ``blur_factor``."""
        out = asdict(self)
        out["blur_factor"] = self.blur_factor
        return out


def apparent_cycles_per_frame(rotor_hz: float, strobe_hz: float) -> float:
    """Alias of the rotor frequency sampled once per flash, in cycles per flash, in [-0.5, 0.5)."""
    r = rotor_hz / strobe_hz
    return r - math.floor(r + 0.5)


def fold(cycles_per_frame: float) -> float:
    """What the footage alone can tell of ``c``: its distance to the nearest integer, in [0, 0.5]."""
    f = cycles_per_frame % 1.0
    return min(f, 1.0 - f)


def choose_phase_model(rotor_hz: float | None, strobe_hz: float | None, apparent_hz: float | None,
                       camera_fps: float | None, exposure_s: float | None,
                       file_fps: float) -> PhaseModel | None:
    """The phase model from what the user gave; None means: take it from the signal.

    Raises ValueError with a sentence when the frame rate needed is unknown."""
    fps = camera_fps or file_fps or None
    fps_note = "--camera-fps" if camera_fps else "the file's frame rate"
    if rotor_hz and strobe_hz:
        fps = fps or strobe_hz
        m = round(rotor_hz / strobe_hz)
        f_a = rotor_hz - m * strobe_hz
        return PhaseModel(
            "lamp", f_a / fps, fps, f_a, m,
            flashes_per_frame=strobe_hz * exposure_s if exposure_s else strobe_hz / fps,
            cycles_per_exposure=abs(f_a) * exposure_s if exposure_s else None,
            equation="psi_k = 2 pi (f_rot - m f_s) k / F",
            source=f"rotor and strobe frequencies (lamp, harmonic m = {m}) at {fps_note}")
    if rotor_hz:
        if not fps:
            raise ValueError("the file has no frame rate; give --camera-fps (the camera is the strobe)")
        m = round(rotor_hz / fps)
        f_a = rotor_hz - m * fps
        return PhaseModel(
            "camera", f_a / fps, fps, f_a, m, flashes_per_frame=1.0,
            cycles_per_exposure=rotor_hz * exposure_s if exposure_s else None,
            equation="psi_k = 2 pi (f_rot - m F) k / F",
            source=f"rotor frequency, the camera's exposure as the strobe (m = {m}) at {fps_note}")
    if apparent_hz:
        if not fps:
            raise ValueError("the file has no frame rate; give --camera-fps or --rotor-hz and --strobe-hz")
        return PhaseModel("apparent", apparent_hz / fps, fps, apparent_hz,
                          cycles_per_exposure=abs(apparent_hz) * exposure_s if exposure_s else None,
                          equation="psi_k = 2 pi f_a k / F", source=f"apparent frequency at {fps_note}")
    return None


def _explained(psi: np.ndarray, series: list[np.ndarray]) -> float:
    """Mean fraction of each series' variance explained by a sinusoid at phases psi (0..1)."""
    design = np.column_stack([np.ones_like(psi), np.sin(psi), np.cos(psi)])
    total, count = 0.0, 0
    for y in series:
        var = float(np.var(y))
        if var <= 0:
            continue
        coef, *_ = np.linalg.lstsq(design, y, rcond=None)
        total += 1 - float(np.mean((y - design @ coef) ** 2)) / var
        count += 1
    return total / count if count else 0.0


def explained_fraction(frames: np.ndarray, cycles_per_frame: float, series: list[np.ndarray]) -> float:
    return _explained(2 * math.pi * cycles_per_frame * np.asarray(frames, float), series)


GRID_CELLS = 2_000_000  # frequencies x frames evaluated at once by _explained_on_grid


def _explained_on_grid(frames: np.ndarray, grid: np.ndarray, series: list[np.ndarray]) -> np.ndarray:
    """:func:`explained_fraction` at every frequency of ``grid`` at once: the 3 x 3 normal
    equations of ``[1, sin, cos]`` for all frequencies as one stack, solved by pseudo-inverse
    (rank-deficient at 0.5 cycles per frame, where the sine vanishes, as lstsq's minimum norm)."""
    psi = 2 * math.pi * grid[:, None] * frames[None, :]
    s, c = np.sin(psi), np.cos(psi)
    n = float(len(frames))
    normal = np.empty((len(grid), 3, 3))
    normal[:, 0, 0] = n
    normal[:, 0, 1] = normal[:, 1, 0] = s.sum(axis=1)
    normal[:, 0, 2] = normal[:, 2, 0] = c.sum(axis=1)
    normal[:, 1, 1] = (s * s).sum(axis=1)
    normal[:, 1, 2] = normal[:, 2, 1] = (s * c).sum(axis=1)
    normal[:, 2, 2] = (c * c).sum(axis=1)
    inverse = np.linalg.pinv(normal, rcond=1e-10)
    total, count = np.zeros(len(grid)), 0
    for y in series:
        y = np.asarray(y, float)
        var = float(np.var(y))
        if var <= 0:
            continue
        right = np.stack([np.full(len(grid), y.sum()), (s * y).sum(axis=1), (c * y).sum(axis=1)], axis=1)
        coef = np.einsum("gij,gj->gi", inverse, right)
        rss = float(y @ y) - np.einsum("gi,gi->g", coef, right)
        total += 1 - np.maximum(rss, 0.0) / n / var
        count += 1
    return total / count if count else total


@dataclass
class SignalFrequency:
    cycles_per_frame: float  # in (0, 0.5]
    explained: float
    runner_up_cycles_per_frame: float | None
    runner_up_explained: float | None


def estimate_cycles_per_frame(frames: np.ndarray, series: list[np.ndarray]) -> SignalFrequency:
    """Apparent frequency (cycles per frame, in (0, 0.5]) that best explains the series as
    sinusoids: the maximum of the mean explained variance over a fine grid, refined by
    golden-section search; the best peak at least two resolution widths away is the runner-up."""
    k = np.asarray(frames, float)
    n = max(8, int(k.max() - k.min() + 1))
    grid = np.linspace(0.5 / n, 0.5, 8 * n)
    chunk = max(1, GRID_CELLS // max(1, len(k)))  # bounded memory however long the clip
    power = np.concatenate([_explained_on_grid(k, grid[i:i + chunk], series)
                            for i in range(0, len(grid), chunk)])
    i = int(np.argmax(power))
    step = grid[1] - grid[0]
    a, b = max(1e-6, grid[i] - step), min(0.5, grid[i] + step)
    for _ in range(40):
        c1, c2 = b - 0.618 * (b - a), a + 0.618 * (b - a)
        if explained_fraction(k, c1, series) > explained_fraction(k, c2, series):
            b = c2
        else:
            a = c1
    best = 0.5 * (a + b)
    far = np.abs(grid - best) > 2.0 / n
    runner: tuple[float, float] | tuple[None, None] = (None, None)
    if far.any():
        runner = (float(grid[far][int(np.argmax(power[far]))]), float(power[far].max()))
    return SignalFrequency(best, explained_fraction(k, best, series), *runner)
