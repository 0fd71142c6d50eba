"""Synthetic sessions and CSVs in the documented formats (results.json of the protocols issue)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

G0 = 9.80665


def write_sweep_session(root: Path, *, a: float = 224e6, b: float = -1.9, noise: float = 0.01,
                        seed: int = 0, speeds_rpm=None) -> Path:
    """A speed-sweep session: run.json + results.json with points as labkit.protocols writes them."""
    rng = np.random.default_rng(seed)
    speeds = np.arange(6000, 20001, 1000.0) if speeds_rpm is None else np.asarray(speeds_rpm, float)
    grams = a * speeds**b * np.exp(rng.normal(0, noise, speeds.size))
    points = [{"speed_rpm": float(s), "speed_rad_s": float(s * 2 * math.pi / 60), "force_g": float(g),
               "force_n": float(g * 1e-3 * G0), "force_stderr_g": float(g * noise), "n": 20,
               "settle_s": 1.5} for s, g in zip(speeds, grams, strict=True)]
    root.mkdir(parents=True, exist_ok=True)
    (root / "results.json").write_text(json.dumps({
        "protocol": "speed-sweep", "points": points,
        "fit": {"model": "power-law",
                "params": {"a": {"value": a, "stderr": 0}, "b": {"value": b, "stderr": 0}}},
    }))
    (root / "run.json").write_text(json.dumps({
        "rig": {"name": "emulated-fig5.25", "floator": {"mass_g": 6.67, "inertia_kg_m2": 1e-7}},
        "labkit_version": "0.1.0", "start": "2026-11-22T09:00:00Z", "end": "2026-11-22T09:05:00Z",
        "exit_status": "ok", "operator_notes": "synthetic test session",
    }))
    return root


@pytest.fixture
def sweep_session(tmp_path: Path) -> Path:
    return write_sweep_session(tmp_path / "sweep-session")
