"""Synthetic sessions in the documented formats (results.json of the protocols issue)."""

from __future__ import annotations

from pathlib import Path

import pytest

from labkit.fit.synthetic import write_sweep_session


@pytest.fixture
def sweep_session(tmp_path: Path) -> Path:
    return write_sweep_session(tmp_path / "sweep-session")
