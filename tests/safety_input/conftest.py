"""Shared helpers: the shipped emulated rig as text, a way to change one key, the real CLI."""

from __future__ import annotations

from pathlib import Path

import pytest

from labkit.cli import main
from labkit.emulators.plant import reset_plants

REPO = Path(__file__).resolve().parents[2]
FIG525 = REPO / "rigs" / "emulated-fig525.toml"


@pytest.fixture(autouse=True)
def fresh_plants():
    reset_plants()
    yield
    reset_plants()


def rig_with(tmp_path: Path, old: str, new: str, name: str = "rig.toml") -> Path:
    """The shipped Fig. 5.25 rig with the line ``old`` replaced by ``new`` (asserted present)."""
    text = FIG525.read_text()
    assert old in text, old
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


def run_cli(argv: list[str], capsys) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line(code: int, err: str, *needles: str) -> None:
    """Exit 2, exactly one line on stderr containing every needle, and no traceback."""
    assert code == 2, (code, err)
    assert "Traceback" not in err, err
    assert err.count("\n") == 1, err
    for needle in needles:
        assert needle in err, (needle, err)
