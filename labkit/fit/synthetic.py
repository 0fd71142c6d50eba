"""Synthetic sessions with known answers, for checking a fitting or report pipeline.

``write_sweep_session(dir, a=224e6, b=-1.9, noise=0.01, seed=0)`` writes a speed-sweep
session (run.json, results.json) whose forces follow y[g] = a x[rpm]^b with log-normal noise,
in the layout :mod:`labkit.session` writes.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from labkit.units import gf_to_n


def write_sweep_session(root: str | Path, *, a: float = 224e6, b: float = -1.9, noise: float = 0.01,
                        seed: int = 0, speeds_rpm=None) -> Path:
    root = Path(root)
    rng = np.random.default_rng(seed)
    speeds = np.arange(6000, 20001, 1000.0) if speeds_rpm is None else np.asarray(speeds_rpm, float)
    grams = a * speeds**b * np.exp(rng.normal(0, noise, speeds.size))
    points = [{"speed_rpm": float(s), "speed_rad_s": float(s * 2 * math.pi / 60), "force_g": float(g),
               "force_n": float(gf_to_n(g)), "force_stderr_g": float(g * noise),
               "force_stderr_n": float(gf_to_n(g * noise)), "n": 20, "settle_time_s": 1.5}
              for s, g in zip(speeds, grams, strict=True)]
    root.mkdir(parents=True, exist_ok=True)
    (root / "results.json").write_text(json.dumps({
        "protocol": "speed-sweep", "points": points,
        "fit": {"model": "power-law",
                "params": {"a": {"value": a, "stderr": 0}, "b": {"value": b, "stderr": 0}}},
    }))
    (root / "run.json").write_text(json.dumps({
        "protocol": "speed-sweep", "params": {"speeds_rpm": [float(s) for s in speeds]},
        "rig": "emulated-fig5.25", "started": "2026-11-22T09:00:00Z", "ended": "2026-11-22T09:05:00Z",
        "status": "completed", "notes": "synthetic test session",
    }))
    return root
