"""A user's protocol and driver, installed as a package with entry points, run from
``labkit run`` (labkit.plugins). The package is a real dist-info directory on sys.path, so
importlib.metadata finds it exactly as it finds a pip-installed one."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

WORKTREE = Path(__file__).resolve().parents[2]

PLUGIN = '''
from labkit.devices.balance.mtsics import {balance}
from labkit.protocols.speed_sweep import SpeedSweep


class QuickSweep(SpeedSweep):
    """The speed sweep with three default speeds: a user's own protocol."""
    name = "quick-sweep"
    defaults = dict(SpeedSweep.defaults, speeds_rpm=[6000.0, 8000.0, 10000.0], record_s=1.0)


class MyBalance({balance}):
    """A user's balance driver (here: MT-SICS under another protocol name)."""
    protocol = "my_balance"
'''


def install_plugin(site: Path, entry_points: str) -> None:
    from labkit.devices.registry import driver_class

    balance = driver_class("balance", "mtsics").__name__
    (site / "mylab_plugin").mkdir(parents=True)
    (site / "mylab_plugin" / "__init__.py").write_text(PLUGIN.format(balance=balance))
    info = site / "mylab_plugin-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: mylab-plugin\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(entry_points)


def labkit(args: list[str], cwd: Path, site: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(WORKTREE), str(site)]))
    return subprocess.run([sys.executable, "-m", "labkit", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)


def test_an_installed_protocol_and_driver_run_from_labkit_run(tmp_path: Path) -> None:
    site = tmp_path / "site"
    install_plugin(site, "[labkit.protocols]\nquick-sweep = mylab_plugin:QuickSweep\n\n"
                         "[labkit.drivers]\nmy-balance = mylab_plugin:MyBalance\n")
    rig = (WORKTREE / "rigs" / "emulated-fig525.toml").read_text()
    assert 'protocol = "mtsics"' in rig
    (tmp_path / "my-rig.toml").write_text(rig.replace('protocol = "mtsics"', 'protocol = "my_balance"'))
    done = labkit(["run", "my-rig.toml", "quick-sweep", "--sessions", "s", "--no-progress", "--json", "-"],
                  tmp_path, site)
    assert done.returncode == 0, done.stderr
    outcome = json.loads(done.stdout)
    assert outcome["status"] == "completed"
    assert [round(p["target_rpm"]) for p in outcome["results"]["points"]] == [6000, 8000, 10000]
    run_json = json.loads((Path(tmp_path / outcome["session"]) / "run.json").read_text())
    assert run_json["protocol"] == "quick-sweep"


def test_a_broken_plugin_is_named_and_built_ins_still_work(tmp_path: Path) -> None:
    site = tmp_path / "site"
    install_plugin(site, "[labkit.protocols]\nbroken = mylab_plugin:NoSuchClass\n")
    done = labkit(["run", "emulated-fig525", "broken", "--dry-run"], tmp_path, site)
    assert done.returncode == 2
    (line,) = done.stderr.strip().splitlines()
    assert "unknown protocol 'broken'" in line
    assert "labkit.protocols:broken (mylab-plugin): cannot load mylab_plugin:NoSuchClass" in line
    ok = labkit(["run", "emulated-fig525", "speed-sweep", "--dry-run"], tmp_path, site)
    assert ok.returncode == 0, ok.stderr
