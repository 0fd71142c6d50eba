"""``labkit rig new KIND FILE``: the templates ship in the package and are written, never over
an existing file (issue 18, item 6)."""

from __future__ import annotations

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from labkit.cli import main
from labkit.rig import load_rig

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize(("kind", "protocol"),
                         [("balance", "speed-sweep"), ("spin-critical", "spin-critical")])
def test_rig_new_writes_a_valid_template_and_names_it(kind, protocol, tmp_path, capsys) -> None:
    out = tmp_path / "my-rig.toml"
    assert main(["rig", "new", kind, str(out)]) == 0
    captured = capsys.readouterr()
    assert f"wrote {out}" in captured.err
    assert f"labkit run {out} {protocol} --dry-run" in captured.out
    assert out.read_text() == (REPO / "rigs" / f"template-{kind}.toml").read_text()
    rig = load_rig(out)
    assert {"rotor_motor", "rotor_tach", "balance"} <= set(rig.devices)


def test_rig_new_refuses_to_overwrite(tmp_path, capsys) -> None:
    out = tmp_path / "my-rig.toml"
    out.write_text("# mine\n")
    assert main(["rig", "new", "balance", str(out)]) == 2
    assert "exists; not overwritten" in capsys.readouterr().err
    assert out.read_text() == "# mine\n"


def test_rig_new_unknown_kind_names_the_known_ones(tmp_path, capsys) -> None:
    assert main(["rig", "new", "balanse", str(tmp_path / "x.toml")]) == 2
    assert "known: balance, spin-critical" in capsys.readouterr().err
    assert not (tmp_path / "x.toml").exists()


def test_packaged_templates_are_the_repository_templates() -> None:
    for kind in ("balance", "spin-critical"):
        packaged = REPO / "labkit" / "data" / "templates" / f"{kind}.toml"
        assert packaged.read_text() == (REPO / "rigs" / f"template-{kind}.toml").read_text(), (
            f"copy rigs/template-{kind}.toml to {packaged.relative_to(REPO)}")


@pytest.mark.slow
@pytest.mark.timeout(600)
def test_the_wheel_ships_templates_rigs_and_py_typed(tmp_path) -> None:
    src = tmp_path / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        (src / name).write_bytes((REPO / name).read_bytes())
    subprocess.run(["cp", "-r", str(REPO / "labkit"), str(src / "labkit")], check=True)
    done = subprocess.run([sys.executable, "-m", "pip", "wheel", str(src), "--no-deps", "-q",
                           "-w", str(tmp_path / "dist")], capture_output=True, text=True, timeout=540,
                          env=dict(os.environ, PIP_DISABLE_PIP_VERSION_CHECK="1"))
    if done.returncode and ("No matching distribution" in done.stderr or "Could not find" in done.stderr):
        pytest.skip(f"no package index to fetch the build backend from: {done.stderr.strip()[-200:]}")
    assert done.returncode == 0, done.stderr[-2000:]
    (wheel,) = (tmp_path / "dist").glob("labkit-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    for name in ("labkit/py.typed", "labkit/data/templates/balance.toml",
                 "labkit/data/templates/spin-critical.toml", "labkit/data/rigs/emulated-fig525.toml"):
        assert name in names, f"{name} missing from {wheel.name}"
