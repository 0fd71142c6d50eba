"""The twin's camera in the loop: ``cone-sweep`` on the model plant, filmed by the emulated camera
(``sim://camera``), the cone angle at ``FOOTAGE_RPM`` from its Eq. 5.24 fit against the model's.

Where :mod:`labkit.twin.footage` renders clips of the model's motion at one speed, offline, this
runs the protocol a user runs: the speed loop settles the model plant's rotor at each speed, the
camera films the model's cone there (the co-rotating steady state of the rig's magnets, as
:func:`labkit.twin.footage.model_motion` computes it), ``analyse laser`` reads each burst, and the
fit of Eq. 5.24 over the ``ok`` points (the live view's ``cone-angle`` fit, torques over I, with
its 95 % band by the delta method) gives the cone angle at ``FOOTAGE_RPM``: the row
``twin/camera/cone_angle``, beside ``twin/laser/cone_angle`` from the rendered clips.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from labkit.emulators.twin_model import TwinParams
from labkit.errors import LabkitError

#: the cone-sweep plan of the twin: 4 000-9 000 RPM around the footage's 6 000 RPM
CAMERA_SETS = ["speeds_rpm=4000:9000:1000", "burst_frames=20"]


def camera_rows(user_rig: Path, params: TwinParams, work: Path, seed: int) -> tuple[list[dict], dict]:
    """Row ``twin/camera/cone_angle``; the run's session, points and the largest point error."""
    from labkit.stream.livefit import cone_angle_fit
    from labkit.twin.footage import FOOTAGE_RPM, model_motion
    from labkit.twin.protocol_run import run_protocol
    from labkit.twin.recovery import compare
    from labkit.twin.rigtext import write_twin_rig

    rig_file = write_twin_rig(user_rig, "camera", work / "rigs")
    outcome = run_protocol(rig_file, "cone-sweep", CAMERA_SETS, work / "sessions", seed)
    points = outcome.results["points"]
    ok = [p for p in points if p.get("verdict") == "ok" and p.get("cone_angle_rad")]
    fit = cone_angle_fit([p["speed_rad_s"] for p in ok], [p["cone_angle_rad"] for p in ok])
    if fit is None:
        raise LabkitError(f"labkit twin: cone-sweep on the model plant gave {len(ok)} ok point(s) of "
                          f"{len(points)}; Eq. 5.24 needs 3 to fit with an interval")
    w = FOOTAGE_RPM * math.pi / 30.0
    y, lo, hi = (float(v[0]) for v in fit.curve([w]))
    from scipy.stats import t as student_t

    stderr = (hi - lo) / 2 / float(student_t.ppf(0.975, fit.n - 2))
    recovered = {"value": y, "stderr": stderr, "ci95": [lo, hi], "n": fit.n}
    put_in = model_motion(params, FOOTAGE_RPM)["phi"]
    worst = max((abs(p["cone_angle_rad"] / p["model_cone_angle_rad"] - 1) for p in ok
                 if p.get("model_cone_angle_rad")), default=math.nan)
    info: dict[str, Any] = {"session": str(outcome.session), "points": points, "rpm": FOOTAGE_RPM,
                            "fit": {k: {"value": v, "stderr": s} for k, (v, s) in fit.params.items()},
                            "largest_point_rel_diff": worst}
    return [compare("camera", "cone_angle", put_in, recovered, "rad")], info
