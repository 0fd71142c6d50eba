"""sim:// in a fresh interpreter, where no test has imported labkit.emulators yet: the transport
alone refuses it with one line saying what to import; the commands that take port URLs
(``labkit probe``, ``labkit run``) open it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def fresh(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=REPO)


def test_the_transport_alone_names_the_package_that_serves_sim():
    out = fresh("from labkit.io import open_port\n"
                "try:\n    open_port('sim://mtsics')\nexcept Exception as e:\n    print(type(e).__name__, e)")
    assert "PortURLError" in out.stdout and "served by labkit.emulators" in out.stdout, out.stderr


def test_labkit_probe_opens_a_sim_port():
    out = fresh("import sys\nfrom labkit.cli import main\n"
                "sys.exit(main(['probe', 'balance', '--protocol', 'mtsics', '--port', 'sim://mtsics?seed=3',"
                " '--samples', '1', '--json']))")
    assert out.returncode == 0, out.stderr
    reading = json.loads(out.stdout.strip().splitlines()[-1])
    assert reading["unit"] == "kg" and "flags" in reading and "raw" in reading


def test_labkit_run_on_an_emulated_rig(tmp_path):
    out = fresh("import sys\nfrom labkit.cli import main\n"
                "sys.exit(main(['run', 'rigs/emulated-fig525.toml', 'speed-sweep', '--set',"
                f" 'speeds_rpm=6000:9000:3000', '--set', 'record_s=0.5', '--sessions', {str(tmp_path)!r},"
                " '--no-progress']))")
    assert out.returncode == 0 and "completed 2 points" in out.stdout, out.stderr
