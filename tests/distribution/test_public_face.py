"""``import labkit``: a flat, typed, lazy public face (issue 18, item 5)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import labkit

HEAVY = ("numpy", "pandas", "scipy", "matplotlib", "cv2", "rerun", "numba", "pyarrow")


def test_import_labkit_pulls_in_no_heavy_package() -> None:
    code = ("import sys, json, labkit; "
            f"print(json.dumps([m for m in {list(HEAVY)!r} if m in sys.modules]))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout) == []


def test_every_public_name_resolves_and_all_lists_them() -> None:
    assert sorted(labkit.__all__) == sorted([*labkit._FACE, "fit_data", "__version__"])
    for name in labkit.__all__:
        assert getattr(labkit, name) is not None, name
    assert callable(labkit.load_session) and callable(labkit.analyse_laser)
    assert "load_rig" in dir(labkit)


def test_an_unknown_name_is_an_attribute_error() -> None:
    try:
        labkit.no_such_thing  # noqa: B018
    except AttributeError as exc:
        assert "no_such_thing" in str(exc)
    else:
        raise AssertionError("labkit.no_such_thing resolved")


def test_the_package_is_marked_typed() -> None:
    assert (Path(labkit.__file__).parent / "py.typed").is_file()
    pyproject = (Path(__file__).resolve().parents[2] / "pyproject.toml").read_text()
    assert '"py.typed"' in pyproject
