"""Record real-clock sessions the way a lab does, for recordings/sessions/real-* and for the
faithful-replay acceptance counts (docs/explanation/replay.md).

    python analysis/record_real_sessions.py [NAME ...] [--out recordings/sessions]
    python analysis/record_real_sessions.py --repeat 10 --out /tmp/acc sweep-5-inprocess

Each recording is `labkit run ... --clock real` in its own process. All but the ``inprocess``
ones (emulated ``sim://`` ports in labkit's own process) run on the pseudo-terminals of
`labkit emulate` in another process (the rig file rewritten to the ptys, as
tests/safety/harness.py does), so the bytes cross real ptys on the real clock, as with a USB
adapter. Options per recording:

* ``busy``: that many busy loops (``python -c "while True: pass"``) run during the recording,
  so the scheduler delays labkit's threads as on a loaded lab PC;
* ``rig_changes``: ``{old: new}`` text replaced in the rig file (a camera's frame rate);
* ``unplug``: ``(role, step)``: `labkit emulate --unplug-on-usr1 ROLE` pulls that cable 1.5 s
  after the step (1-based) begins.

With ``--replay`` each recording is replayed (``labkit replay``) and the exit status printed,
which is how the 10-out-of-10 counts in docs/explanation/replay.md were made.
"""

from __future__ import annotations

import argparse
import json
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
RIGS = REPO / "rigs"
PY = sys.executable

SWEEP_FIXTURE = ["speeds_rpm=6000:14000:step=2000", "record_s=1.0", "zero=start"]
SWEEP_ACCEPT = ["speeds_rpm=6000:14000:step=2000"]
SPIN = ["start_rpm=6600", "stop_rpm=9000", "step_pct=15", "max_trials=2", "consistent_n=2",
        "consistency_pct=10"]
SPIN_FIXTURE = ["start_rpm=6600", "stop_rpm=8000", "step_pct=15", "max_trials=2", "consistent_n=2",
                "consistency_pct=10"]
STROBE_FIXTURE = ["speeds_rpm=4000:6000:step=1000", "burst_frames=40"]
CONE_FIXTURE = ["speeds_rpm=6000:10000:step=2000", "burst_frames=10"]

RECORDINGS: dict[str, dict] = {
    # shipped fixtures (recordings/sessions/real-*)
    "real-speed-sweep": dict(rig="emulated-fig525.toml", protocol="speed-sweep", sets=SWEEP_FIXTURE),
    "real-speed-sweep-busy": dict(rig="emulated-fig525.toml", protocol="speed-sweep", sets=SWEEP_FIXTURE,
                                  busy=2, inprocess=True),
    "real-speed-sweep-tach-unplug": dict(rig="emulated-fig525.toml", protocol="speed-sweep",
                                         sets=SWEEP_FIXTURE, unplug=("rotor_tach", 3)),
    "real-spin-critical": dict(rig="emulated-fig618.toml", protocol="spin-critical", sets=SPIN_FIXTURE),
    # the emulated strobe lights the emulated camera only inside labkit's process (the camera asks
    # the strobe emulator through the model plant, ADR 0025): no ptys for this rig
    # (the camera emulator draws each frame on the real clock: at 320x240 and 30 a second on a
    # loaded 2-core box it dropped frames and starved the tachometer's emulator; so 160x120 at
    # 0.4 mm per pixel, 15 a second, and the tachometer timeout of a loaded CI box)
    "real-strobe-sweep": dict(rig="emulated-strobe.toml", protocol="strobe-sweep", sets=STROBE_FIXTURE,
                              inprocess=True, rig_changes={
                                  "size=320x240&fps=30&": "size=160x120&fps=15&",
                                  "mm_per_px=0.2&": "mm_per_px=0.4&",
                                  "tach_timeout_s = 0.5": "tach_timeout_s = 2.0"}),
    # the labkit strobe sketch (firmware/labkit_strobe) on a simulated ATmega328P (simavr) behind
    # a pty; no camera: a synthetic clip per step (record_sketch)
    "real-sketch-strobe-sweep": dict(rig="emulated-strobe.toml", protocol="strobe-sweep",
                                     sketch="labkit_strobe", speeds_rpm=[4000.0, 5000.0], divider=4),
    # the emulated camera renders the model plant in labkit's own process (a camera is no serial
    # device `labkit emulate` could serve on a pty), so the motor and tachometer driving that
    # plant run in process too: a real-clock run on sim:// ports
    "real-cone-sweep": dict(rig="emulated-camera.toml", protocol="cone-sweep", sets=CONE_FIXTURE,
                            inprocess=True),
    "spin-3-emulate": dict(rig="emulated-fig618.toml", protocol="spin-critical", sets=SPIN),
    # acceptance (the 5-step sweep, 6000-14000 RPM, default averaging), not shipped
    "sweep-5-inprocess": dict(rig="emulated-fig525.toml", protocol="speed-sweep", sets=SWEEP_ACCEPT,
                              inprocess=True),
    "sweep-5-busy": dict(rig="emulated-fig525.toml", protocol="speed-sweep", sets=SWEEP_ACCEPT,
                         inprocess=True, busy=2),
    "sweep-5-emulate": dict(rig="emulated-fig525.toml", protocol="speed-sweep", sets=SWEEP_ACCEPT),
}


def labkit(*args: str) -> list[str]:
    return [PY, "-m", "labkit", *args]


def pty_rig(rig_text: str, paths: dict[str, str]) -> str:
    """The rig file with every emulated port replaced by its pty, and labkit's side given the
    generous reply and tachometer timeouts of tests/safety/harness.py (a loaded CI box)."""
    for role, path in paths.items():
        start = rig_text.index(f"[devices.{role}]")
        line_start = rig_text.index('port = "sim://', start)
        line_end = rig_text.index("\n", line_start)
        rig_text = rig_text[:line_start] + f'port = "{path}"' + rig_text[line_end:]
    return (rig_text.replace("options = { command_timeout_ms = 500 }",
                             "options = { command_timeout_ms = 500, reply_timeout_s = 1.0 }")
            .replace("tach_timeout_s = 0.5", "tach_timeout_s = 2.0"))


def step_began(sessions: Path, step: int) -> bool:
    """Whether the run's events.jsonl holds the start of ``step`` (1-based)."""
    for events in sessions.glob("*/events.jsonl"):
        for line in events.read_text().splitlines():
            if line.startswith('{"type":"step"') and f'"index":{step - 1},' in line:
                return True
    return False


def record_one(spec: dict, workdir: Path) -> tuple[int, Path | None, str]:
    """Run one recording; ``(exit status, session folder, stderr)``."""
    rig_text = (RIGS / spec["rig"]).read_text()
    for old, new in spec.get("rig_changes", {}).items():
        assert old in rig_text, (spec["rig"], old)
        rig_text = rig_text.replace(old, new)
    sessions = workdir / "sessions"
    procs: list[subprocess.Popen] = []
    try:
        procs += [subprocess.Popen([PY, "-c", "while True: pass"]) for _ in range(spec.get("busy", 0))]
        if spec.get("inprocess"):
            rig = workdir / spec["rig"]
            rig.write_text(rig_text)
        else:
            unplug = ["--unplug-on-usr1", spec["unplug"][0]] if spec.get("unplug") else []
            served = workdir / "served.toml"
            served.write_text(rig_text)
            emulate = subprocess.Popen(labkit("emulate", str(served), "--json", *unplug),
                                       stdout=subprocess.PIPE, text=True, cwd=REPO)
            procs.append(emulate)
            paths = json.loads(emulate.stdout.readline())
            rig = workdir / f"pty-{spec['rig']}"
            rig.write_text(pty_rig(rig_text, paths))
        sets = [a for s in spec["sets"] for a in ("--set", s)]
        run = subprocess.Popen(labkit("run", str(rig), spec["protocol"], *sets, "--clock", "real",
                                      "--sessions", str(sessions), "--no-progress"),
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO)
        if spec.get("unplug"):
            step = spec["unplug"][1]
            while run.poll() is None and not step_began(sessions, step):
                time.sleep(0.05)
            time.sleep(1.5)
            procs[-1].send_signal(signal.SIGUSR1)
        _, err = run.communicate(timeout=900)
    finally:
        for proc in procs:
            proc.terminate()
            proc.wait(timeout=10)
    found = sorted(sessions.glob("*"))
    return run.returncode, (found[-1] if found else None), err


class Harness:
    """A sketch on the simavr harness (firmware/sim/labkit_simavr.c, built by firmware/build.py):
    its UART's pty, and the rotor's once-per-revolution pulse on ICP1 set from stdin."""

    def __init__(self, sketch: str, build: Path, built: dict[str, Path] | None = None) -> None:
        """``built``: the sketch's .hex and the harness already built (``{sketch: hex, "harness":
        path}``, as tests/firmware/conftest.py builds them), else built into ``build``."""
        if built is not None:
            hex_file, harness = built[sketch], built["harness"]
        else:
            hex_file, harness = (self._build([str(REPO / "firmware" / sketch)], build),
                                 self._build(["--harness"], build))
        self.proc = subprocess.Popen([str(harness), str(hex_file)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True, bufsize=1)
        assert self.proc.stdout is not None
        words: list[str] = []
        while words[:1] != ["PTY"]:  # simavr's own lines come first
            line = self.proc.stdout.readline()
            assert line, "the simavr harness ended before printing its PTY line"
            words = line.split()
        self.pty = words[1]
        # the harness prints every edge and flash: drained, or it blocks on a full pipe
        threading.Thread(target=lambda: [None for _ in self.proc.stdout or ()], daemon=True).start()

    @staticmethod
    def _build(args: list[str], out: Path) -> Path:
        done = subprocess.run([PY, str(REPO / "firmware" / "build.py"), *args, "--out", str(out)],
                              capture_output=True, text=True, check=True)
        return Path(done.stdout.strip().splitlines()[-1])

    def rotor(self, hz: float) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(f"icp {hz} ramp 0 low_us 20\n")
        self.proc.stdin.flush()

    def close(self) -> None:
        if self.proc.poll() is None:
            assert self.proc.stdin is not None
            self.proc.stdin.write("quit\n")
            self.proc.stdin.flush()
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=5)


def sketch_rig(rig_text: str, pty: str) -> str:
    """emulated-strobe.toml without its camera, the strobe on the sketch's pty (boot and reply
    timeouts for a simulated MCU on a loaded box), the tachometer timeout of a loaded CI box."""
    rig_text = rig_text[:rig_text.index("[devices.camera]")] + rig_text[rig_text.index("[bodies.rotator]"):]
    rig_text = rig_text.replace('port = "sim://labkit_strobe?seed=5&plant=model-fig525&role=strobe"',
                                f'port = "{pty}"')
    return (rig_text.replace("options = { offset_hz = 1.0, width_us = 20, rate_hz = 10 }",
                             "options = { offset_hz = 1.0, width_us = 20, rate_hz = 10, boot_timeout_s = 10, "
                             "reply_timeout_s = 3 }")
            .replace("tach_timeout_s = 0.5", "tach_timeout_s = 2.0"))


def record_sketch(spec: dict, workdir: Path, clips: Path,
                  built: dict[str, Path] | None = None) -> tuple[int, Path | None, str]:
    """strobe-sweep with the strobe sketch on simavr: the rotor's pulse on the simulated MCU's
    ICP1 pin is set by this script to each step's target speed when the step begins (the
    emulated motor's plant does not drive the simulated pin); the camera is replaced by a
    synthetic clip per step (``labkit synth strobe``, flashes at the strobe's frequency for that
    speed, divider and 1 Hz offset), written to ``clips`` (recorded as a path relative to the
    repository, so the fixture replays from a checkout)."""
    speeds, divider, clip_s = spec["speeds_rpm"], spec["divider"], spec.get("clip_s", 2.0)
    clips.mkdir(parents=True, exist_ok=True)
    for i, rpm in enumerate(speeds):
        rotor_hz = rpm / 60.0
        subprocess.run(labkit("synth", "strobe", str(clips / f"step-{i}.avi"), "--rotor-hz", f"{rotor_hz}",
                              "--strobe-hz", f"{(rotor_hz - 1.0) / divider}", "--frames", "40",
                              "--seed", str(i + 1)), check=True, cwd=REPO, capture_output=True)
    sessions = workdir / "sessions"
    harness = Harness(spec["sketch"], workdir / "firmware", built)
    try:
        harness.rotor(speeds[0] / 60.0)
        rig = workdir / "sketch-strobe.toml"
        rig.write_text(sketch_rig((RIGS / spec["rig"]).read_text(), harness.pty))
        sets = ["--set", "speeds_rpm=" + ",".join(f"{v:g}" for v in speeds), "--set", f"divider={divider}",
                "--set", f"clips={clips.relative_to(REPO) if clips.is_relative_to(REPO) else clips}",
                "--set", "mm_per_px=0.2", "--set", f"clip_s={clip_s:g}"]
        run = subprocess.Popen(labkit("run", str(rig), spec["protocol"], *sets, "--clock", "real",
                                      "--sessions", str(sessions), "--no-progress"),
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO)
        step = 1
        while run.poll() is None:
            if step < len(speeds) and step_began(sessions, step + 1):
                harness.rotor(speeds[step] / 60.0)
                step += 1
            time.sleep(0.05)
        _, err = run.communicate(timeout=900)
    finally:
        harness.close()
    found = sorted(sessions.glob("*"))
    return run.returncode, (found[-1] if found else None), err


def replay(session: Path) -> tuple[int, str, dict[str, float]]:
    """``labkit replay`` of a session: exit status, its output, and the worst relative deviation
    of each number of the replayed points from results.json (:func:`worst_deviations`)."""
    with tempfile.TemporaryDirectory() as tmp:
        report = Path(tmp) / "replay.json"
        done = subprocess.run(labkit("replay", str(session), "--json", str(report)), capture_output=True,
                              text=True, cwd=REPO)
        replayed = json.loads(report.read_text()).get("results") if report.is_file() else None
    recorded = json.loads((session / "results.json").read_text())
    return done.returncode, (done.stdout + done.stderr).strip(), worst_deviations(replayed, recorded)


def summary(text: str) -> str:
    """The line of a replay's output saying what it reproduced, with the camera's line."""
    lines = text.splitlines()
    said = [x.strip() for x in lines if x.startswith(("replayed", "re-analysed")) or x.strip().startswith(
        "camera:")]
    return "; ".join(said) or lines[0]


def worst_deviations(replayed: dict | None, recorded: dict) -> dict[str, float]:
    """Per point key, the largest ``|replay - recording| / |recording|`` over the points."""
    worst: dict[str, float] = {}
    for again, point in zip((replayed or {}).get("points", []), recorded.get("points", []), strict=False):
        for key, value in point.items():
            other = again.get(key)
            if isinstance(value, int | float) and isinstance(other, int | float) and value \
                    and not isinstance(value, bool) and key != "step":
                worst[key] = max(worst.get(key, 0.0), abs(other - value) / abs(value))
    return worst


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("names", nargs="*", default=[n for n in RECORDINGS if n.startswith("real-")])
    parser.add_argument("--out", default=str(REPO / "recordings" / "sessions"))
    parser.add_argument("--repeat", type=int, default=1, help="recordings of each name (NAME-1, NAME-2...)")
    parser.add_argument("--replay", action="store_true", help="replay each recording and count exit 0")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for name in args.names:
        passed = 0
        worst: dict[str, float] = {}
        for i in range(args.repeat):
            target = out / (name if args.repeat == 1 else f"{name}-{i + 1}")
            with tempfile.TemporaryDirectory() as tmp:
                spec = RECORDINGS[name]
                if spec.get("sketch"):  # the clips go into the fixture itself, made before the run
                    if target.exists():
                        shutil.rmtree(target)
                    status, session, err = record_sketch(spec, Path(tmp), target / "clips")
                else:
                    status, session, err = record_one(spec, Path(tmp))
                if session is None:
                    print(f"{target.name}: no session (exit {status}): {err.strip()[-300:]}")
                    continue
                if target.exists() and not spec.get("sketch"):
                    shutil.rmtree(target)
                shutil.copytree(session, target, dirs_exist_ok=True)
            size = sum(f.stat().st_size for f in target.rglob("*") if f.is_file())
            line = f"{target.name}: run exit {status}, {size / 1e6:.2f} MB"
            if args.replay:
                code, text, deviations = replay(target)
                passed += code == 0
                for key, value in deviations.items():
                    worst[key] = max(worst.get(key, 0.0), value)
                line += f"; replay exit {code}: {summary(text) if code == 0 else text[-400:]}"
            print(line, flush=True)
        if args.replay:
            print(f"{name}: {passed}/{args.repeat} replayed with exit 0", flush=True)
            shown = ", ".join(f"{key} {value:.2e}" for key, value in sorted(worst.items()))
            print(f"{name}: worst relative deviation of the points' numbers: {shown}", flush=True)


if __name__ == "__main__":
    main()
