"""The twin's footage: laser-trace and stroboscope clips of the model's floator motion, rendered by
the independent camera-model renderer (:mod:`labkit.footage`) and analysed by
:mod:`labkit.vision`, which recover the cone angle, the tilt amplitude and the RC offset.

The motion is the model's: the co-rotating steady state of the Fig. 5.25 pair at ``FOOTAGE_RPM``
(:func:`labkit.model.floator_equilibrium.steady_state`) gives the cone angle phi (Eq. 5.7) and
the lateral circle beta of the floator's centre; the RC offset is ``delta = beta / tan(phi)``
(Eq. 5.97). The laser clip is the reflected beam of that cone on a screen (``tan 2 phi`` at the
screen distance); the strobe clip is the side view of the floator (drawn as a cylinder of its
size: a sphere carries a painted line in practice) swinging by phi about its RC, filmed from a
different distance in each clip. Each quantity is measured on ``CLIPS`` clips of independent
phase and sensor noise; the 95 % interval is mean +/- t_{0.975, CLIPS-1} sd / sqrt(CLIPS).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from labkit.emulators.twin_model import TwinParams
from labkit.errors import LabkitError
from labkit.twin.recovery import compare

FOOTAGE_RPM = 6000.0
CLIPS = 4
FPS = 30.0
SCREEN_MM = 500.0
LASER_RADIUS_PX = 150.0
#: strobe clips are filmed from different distances (mm per pixel, one per clip): the tilt that
#: labkit.vision reads off a silhouette depends on its size in pixels (+0.5 % at 0.25 mm/px,
#: -0.3 % at 0.125 mm/px for a 15 mm body), so that error enters the spread of the clips
STROBE_MM_PER_PX = (0.125, 0.17, 0.21, 0.25)


def model_motion(params: TwinParams, rpm: float = FOOTAGE_RPM) -> dict[str, float]:
    """Cone angle phi (rad), lateral amplitude beta (m) and RC offset delta (m) of the model."""
    from labkit.model.floator_equilibrium import FloatorSetup, steady_state
    w = rpm * math.pi / 30.0
    setup = FloatorSetup(params.m_rotator, params.m_floator, params.mass_kg, params.i_radial,
                         params.i_axial, w, params.tilt_rad)
    st = steady_state(setup, params.gap_m)
    return {"phi": st.phi, "beta_m": st.beta, "delta_m": st.beta / math.tan(st.phi), "omega": w}


def _interval(values: list[float]) -> dict[str, Any]:
    import statistics

    from scipy.stats import t as student_t
    mean, sd = statistics.fmean(values), statistics.stdev(values)
    half = float(student_t.ppf(0.975, len(values) - 1)) * sd / math.sqrt(len(values))
    return {"value": mean, "stderr": sd / math.sqrt(len(values)), "ci95": [mean - half, mean + half],
            "n": len(values), "each": values}


def laser_cone_angle(phi: float, work: Path, seed: int, clip: int) -> float:
    """Render one laser clip of a cone of half-angle ``phi`` and return the analysed cone angle."""
    from labkit.footage import (
        Camera,
        LaserShot,
        Lighting,
        PrecessionNutation,
        Screen,
        ScreenView,
        laser_truth,
        render_laser,
        write_footage,
    )
    from labkit.vision.laser.analyse import analyse_laser
    beam = math.tan(2.0 * phi)
    mm_per_px = SCREEN_MM * beam / LASER_RADIUS_PX
    cycle_hz = (2 + 0.381966 + 0.01 * clip) * FPS
    phase = 2.0 * math.pi * ((0.37 * (clip + 1) + 0.11 * seed) % 1.0)
    shot = LaserShot(PrecessionNutation((0.0, 0.0), (beam, 0.0), (0.0, 0.0), -1, cycle_hz, phase),
                     Screen(SCREEN_MM, 0.0, hole_mm=3.0), ScreenView((320.0, 240.0), mm_per_px, 0.0),
                     Camera((640, 480), FPS, 0.6 / cycle_hz, 0.0, read_noise=0.01, shot_noise=0.01,
                            psf_core_px=1.2),
                     Lighting(level=0.03), frames=30, power=1.2, seed=1000 * seed + clip)
    path = write_footage(work / f"laser-{clip}.mp4", render_laser(shot), FPS, laser_truth(shot))
    tilt = analyse_laser(str(path), screen_distance_mm=SCREEN_MM, mm_per_px=mm_per_px).tilt_rad
    return 0.5 * (tilt.major + tilt.minor)


def strobe_swing(phi: float, delta_m: float, body_mm: tuple[float, float], work: Path, seed: int,
                 clip: int) -> tuple[float, float, str]:
    """Render one strobe clip; return the analysed (tilt amplitude rad, RC offset m, verdict)."""
    from labkit.footage import (
        Body,
        Camera,
        Lamp,
        Lighting,
        StrobeShot,
        Swing,
        render_strobe,
        strobe_truth,
        write_footage,
    )
    from labkit.vision.strobe.analyse import analyse_strobe
    scale = STROBE_MM_PER_PX[clip % len(STROBE_MM_PER_PX)]
    length_px, width_px = (x / scale for x in body_mm)
    rotor_hz = 7 * FPS + (0.13 + 0.01 * clip) * FPS         # 7th harmonic, slow apparent motion
    psi0 = 2.0 * math.pi * ((0.29 * (clip + 1) + 0.07 * seed) % 1.0)
    delta_px = delta_m * 1e3 / scale
    shot = StrobeShot(Body("cylinder", length_px, width_px), Swing(phi, delta_px, rotor_hz, psi0),
                      Lamp(FPS, 0.2 / FPS, 20e-6), Camera((640, 480), FPS, 0.5 / FPS, 0.0, read_noise=0.01,
                                                          psf_core_px=1.0),
                      (320.0, 240.0), lighting=Lighting(level=0.0), frames=60, seed=1000 * seed + clip)
    path = write_footage(work / f"strobe-{clip}.mp4", render_strobe(shot), FPS, strobe_truth(shot))
    r = analyse_strobe(str(path), rotor_hz=rotor_hz, strobe_hz=FPS)
    tilt = r.tilt_amplitude_rad
    return tilt, r.lateral_amplitude_px * scale * 1e-3 / math.tan(tilt), r.verdict


def footage_rows(params: TwinParams, work: Path, seed: int) -> tuple[list[dict], dict]:
    """Rows ``twin/laser/cone_angle``, ``twin/strobe/tilt_amplitude``, ``twin/strobe/rc_offset``."""
    motion = model_motion(params)
    folder = work / "footage"
    folder.mkdir(parents=True, exist_ok=True)
    cones = [laser_cone_angle(motion["phi"], folder, seed, k) for k in range(CLIPS)]
    body = (15.0, 7.5)
    every = [strobe_swing(motion["phi"], motion["delta_m"], body, folder, seed, k) for k in range(CLIPS)]
    # a clip the analysis itself calls doubtful or failed (e.g. a body too small for the tilt
    # tolerance at the farthest camera distance) is left out, as a user should leave it out
    swings = [s for s in every if s[2] == "ok"]
    if len(swings) < 2:
        verdicts = ", ".join(s[2] for s in every)
        raise LabkitError(f"twin strobe footage: only {len(swings)} of {len(every)} clips analysed ok "
                          f"({verdicts}); no interval can be formed")
    rows = [compare("laser", "cone_angle", motion["phi"], _interval(cones), "rad"),
            compare("strobe", "tilt_amplitude", motion["phi"], _interval([s[0] for s in swings]), "rad"),
            compare("strobe", "rc_offset", motion["delta_m"], _interval([s[1] for s in swings]), "mm", 1e3)]
    return rows, {"folder": str(folder), "motion": motion, "rpm": FOOTAGE_RPM}
