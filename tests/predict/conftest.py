"""Shared fixtures: the user story's pair (6x3 mm cylinder rotator, 10 mm sphere floator, N42)."""

from __future__ import annotations

import math

import pytest

from labkit.predict.magnets import parse_magnet_spec
from labkit.predict.pair import Pair

RPM = 2 * math.pi / 60


@pytest.fixture(scope="session")
def story_pair() -> Pair:
    return Pair(parse_magnet_spec("cylinder:6x3mm"), parse_magnet_spec("sphere:10mm"), math.radians(5.0))
