"""Shared helpers for the simulator tests."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from labkit.sim import load_scene, scene_from_dict

SCENES = Path(__file__).resolve().parents[2] / "labkit" / "data" / "scenes"


def bundled_dict(name: str) -> dict:
    """A bundled scene's TOML as a dict, to vary in a test."""
    return tomllib.loads((SCENES / f"{name}.toml").read_text())


@pytest.fixture
def conical():
    return load_scene("conical_5_1")


def make(data: dict, source: str = "test.toml"):
    return scene_from_dict(data, source=source)
