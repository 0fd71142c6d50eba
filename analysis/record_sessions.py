"""Regenerate recordings/sessions/: two recorded sessions per protocol on the emulated rigs
(their default model plant, docs/explanation/twin.md: the balance force and the drop come from the rig
file's magnets; the fault recordings add their faults on top).

    python analysis/record_sessions.py [--out recordings/sessions]

* speed-sweep-clean        Fig. 5.25 sweep, 4 speeds, no faults
* speed-sweep-tach-unplug  the rotor tachometer is unplugged mid-sweep: interlock, motor to
                           zero, partial results (status "failed")
* spin-critical-clean      Fig. 6.18 series, 3 speeds
* spin-critical-garbage    garbage bursts on the balance and the spin tachometer
* cone-sweep-clean         the filmed cone angle at 6 speeds (rigs/emulated-camera.toml, issue 25):
                           its camera cassette holds the emulated camera's JPEG frames
* strobe-sweep-clean       phi, beta and delta at 4 speeds under the locked strobe
                           (rigs/emulated-strobe.toml, issue 26): strobe status lines and the
                           strobe-lit frames (0.8 MB as recorded: a crop to the floator saved
                           a third of the frames' bytes and moved phi by 1-2 %, so it is not shrunk)

Each is replayed bit-for-bit by tests/session/test_recorded_sessions.py. The runs use the
virtual clock, so the recordings are deterministic apart from run.json's dates and versions.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
from pathlib import Path

from labkit.protocols.launch import execute, prepare_run

REPO = Path(__file__).resolve().parents[1]
RIGS = REPO / "rigs"

SWEEP = ["speeds_rpm=6000:18000:4000", "record_s=1.0", "zero=start", "min_samples=5"]
SPIN = ["start_rpm=6600", "stop_rpm=9000", "step_pct=15", "max_trials=2", "consistent_n=2",
        "consistency_pct=10"]

RECORDINGS = {
    # name: (rig, {text to replace: replacement}, protocol, --set values)
    "speed-sweep-clean": ("emulated-fig525.toml", {}, "speed-sweep", SWEEP),
    "speed-sweep-tach-unplug": ("emulated-fig525.toml",
                                {"role=rotor_tach&": "role=rotor_tach&faults=disconnect_at:12&"},
                                "speed-sweep", SWEEP),
    "spin-critical-clean": ("emulated-fig618.toml", {}, "spin-critical", SPIN),
    "spin-critical-garbage": ("emulated-fig618.toml",
                              {"role=floator_tach&": "role=floator_tach&faults=garbage:0.05&",
                               "role=balance": "role=balance&faults=garbage:0.03"},
                              "spin-critical", SPIN),
    "cone-sweep-clean": ("emulated-camera.toml", {}, "cone-sweep", ["burst_frames=20"]),
    "strobe-sweep-clean": ("emulated-strobe.toml", {}, "strobe-sweep", ["speeds_rpm=4000:7000:1000"]),
}


def record(name: str, out: Path) -> Path:
    rig_name, changes, protocol, sets = RECORDINGS[name]
    text = (RIGS / rig_name).read_text()
    for old, new in changes.items():
        assert old in text, (name, old)
        text = text.replace(old, new)
    with tempfile.TemporaryDirectory() as tmp:
        rig = Path(tmp) / rig_name
        rig.write_text(text)
        prep = prepare_run(rig, protocol, sets, session_root=Path(tmp) / "s")
        notes = f"recordings/sessions/{name} (analysis/record_sessions.py)"
        outcome = execute(prep, Path(tmp) / "s", notes=notes)
        target = out / name
        if target.exists():
            shutil.rmtree(target)
        shutil.copytree(outcome.session, target)
    size = sum(f.stat().st_size for f in target.rglob("*") if f.is_file())
    print(f"{name}: {outcome.status} ({outcome.reason or 'ok'}), "
          f"{len(outcome.results['points'])} points, {size / 1e6:.2f} MB")
    return target


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=str(REPO / "recordings" / "sessions"))
    parser.add_argument("names", nargs="*", default=list(RECORDINGS))
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for name in args.names:
        record(name, out)


if __name__ == "__main__":
    main()
