"""``sim://camera?scene=strobe``: the emulated camera filming the floator side on, lit only by
the flashes of the plant's emulated strobe (``sim://labkit_strobe``, issue 26).

The model plant's rotor speed gives the floator's co-rotating steady state
(:func:`labkit.model.floator_equilibrium.steady_state`, as ``labkit twin`` uses it): the tilt
amplitude phi (Eq. 5.7), the lateral amplitude beta of the centre of mass, and the RC offset
``delta = beta / tan(phi)`` (Eq. 5.97). The floator swings as Eq. 5.97 says (tilt
``phi sin psi``, ``psi`` the rotor's angle) and is drawn as a cylinder of ``body_mm``
(length x width; a sphere carries a painted line in practice) against a background the flashes
light, by :mod:`labkit.footage` (:func:`~labkit.footage.render_strobe`) at ``mm_per_px``.

The flashes are the strobe emulator's (:meth:`~labkit.emulators.strobes.LabkitStrobeEmulator.flash_plan`):
locked to the rotor's pulse, every ``m``-th revolution, each one ``offset`` revolutions per
second later in rotor angle, so the rotor's angle at a flash is ``2 pi offset t`` (mod 2 pi)
whatever the speed: at a steady speed f they fall at ``j m / (f - offset)``. A dark strobe
(off, rotor out of range, not yet locked, no strobe on the plant) leaves the frame black.

Each frame's ``meta`` carries the model's truth at the frame's true rotor speed
(``model_phi_rad``, ``model_beta_mm``, ``model_delta_mm``, ``model_speed_rad_s``) and
``lit`` (the strobe flashed); the frame cassette stores it, so a replay has it too.
Options (URL query): ``strobe`` (role of the strobe emulator, ``strobe``), ``body_mm``
(``15x7.5``), ``mm_per_px`` (0.2), ``ambient`` (room light during the exposure relative to
the flashes, 0).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

from labkit.devices.camera.sources import SourceStopped

#: the URL options of the strobe scene and their defaults (as the URL would give them)
STROBE_DEFAULTS: dict[str, str] = {"strobe": "strobe", "body_mm": "15x7.5", "mm_per_px": "0.2",
                                   "ambient": "0"}


@lru_cache(maxsize=512)
def model_swing(params: Any, rpm: int) -> tuple[float, float, float]:
    """(phi rad, beta m, delta m) of the model's co-rotating steady state at ``rpm`` (whole RPM:
    cached); (0, 0, 0) where there is none (rotor too slow, no solution)."""
    if rpm < 500:
        return 0.0, 0.0, 0.0
    from labkit.model.floator_equilibrium import FloatorSetup, steady_state

    setup = FloatorSetup(params.m_rotator, params.m_floator, params.mass_kg, params.i_radial,
                         params.i_axial, rpm * math.pi / 30.0, params.tilt_rad)
    try:
        st = steady_state(setup, params.gap_m)
        phi, beta = float(st.phi), float(st.beta)
    except Exception:  # noqa: BLE001 - no steady state: the floator does not follow; a still body
        return 0.0, 0.0, 0.0
    if not (math.isfinite(phi) and math.isfinite(beta) and 0 < phi < math.pi / 4):
        return 0.0, 0.0, 0.0
    return phi, abs(beta), abs(beta) / math.tan(phi)


def _body_mm(text: str) -> tuple[float, float]:
    length, sep, width = text.partition("x")
    try:
        size = (float(length), float(width)) if sep else None
    except ValueError:
        size = None
    if size is None or not all(0 < v < 1000 for v in size):
        raise SourceStopped(f"body_mm={text!r}: expected LENGTHxWIDTH in mm, e.g. 15x7.5")
    return size


class StrobeScene:
    """The side view of the floator lit by the plant's strobe (module docstring)."""

    def __init__(self, camera: Any, options: dict[str, str]) -> None:
        self.camera = camera
        self.strobe_role = options.get("strobe", STROBE_DEFAULTS["strobe"])
        self.body_mm = _body_mm(options.get("body_mm", STROBE_DEFAULTS["body_mm"]))
        self.mm_per_px = float(options.get("mm_per_px", STROBE_DEFAULTS["mm_per_px"]))
        self.ambient = float(options.get("ambient", STROBE_DEFAULTS["ambient"]))
        if not (self.mm_per_px > 0 and 0 <= self.ambient <= 10):
            raise SourceStopped(f"mm_per_px={self.mm_per_px:g} must be > 0 and ambient={self.ambient:g} "
                                "within 0..10")
        w, h = camera.size
        if max(self.body_mm) / self.mm_per_px > 0.45 * min(w, h):
            raise SourceStopped(f"a {self.body_mm[0]:g} mm body at {self.mm_per_px:g} mm/px does not fit a "
                                f"{w}x{h} frame with room to swing (at most 45 % of its height)")

    def truth(self, t: float) -> dict[str, Any]:
        """The model at the true rotor speed at clock time ``t`` and whether the strobe flashes."""
        cam = self.camera
        w = abs(cam.plant.speed(t))
        phi, beta, delta = model_swing(cam.params, int(round(w * 30.0 / math.pi)))
        strobe = cam.plant.strobes.get(self.strobe_role)
        lit = strobe is not None and strobe.flash_plan(t) is not None
        return {"model_phi_rad": phi, "model_beta_mm": beta * 1e3, "model_delta_mm": delta * 1e3,
                "model_speed_rad_s": w, "lit": lit, "mm_per_px": self.mm_per_px}

    def render(self, start: float, k: int) -> Any:
        """Frame ``k`` (exposure from ``start``) as an 8-bit BGR image."""
        from labkit.footage import Body, Camera, Lamp, Lighting, StrobeShot, Swing, render_strobe

        cam = self.camera
        strobe = cam.plant.strobes.get(self.strobe_role)
        plan = strobe.flash_plan(start) if strobe is not None else None
        w = abs(cam.plant.speed(start))
        phi, _, delta = model_swing(cam.params, int(round(w * 30.0 / math.pi)))
        if plan is None:  # dark: a lamp flashing every 1000 s, half a period (500 s) from this exposure
            lamp, swing = Lamp(1e-3, 500.0), Swing(0.0, 0.0, 1.0, 0.0)
        else:
            f_rot, offset, divider, width_s = plan
            f_strobe = (f_rot - offset) / divider
            j = math.ceil(start * f_strobe - 1e-9)           # the next flash of the steady grid
            tau0 = j / f_strobe - start
            seen = offset * (j / f_strobe) % 1.0              # rotor angle at that flash, revolutions
            psi0 = 2.0 * math.pi * ((seen - f_rot * tau0) % 1.0)
            lamp = Lamp(f_strobe, tau0, width_s)
            swing = Swing(phi, delta * 1e3 / self.mm_per_px, f_rot, psi0)
        w_px, h_px = cam.size
        length, width = (v / self.mm_per_px for v in self.body_mm)
        shot = StrobeShot(Body("cylinder", length, width), swing, lamp,
                          Camera(tuple(cam.size), cam.fps, cam.exposure_s, 0.0, read_noise=0.004,
                                 shot_noise=0.004, psf_core_px=1.0),
                          (w_px / 2, h_px / 2), lighting=Lighting(level=0.0), ambient=self.ambient,
                          frames=1, seed=1000 * cam.seed + k)
        return next(render_strobe(shot))
