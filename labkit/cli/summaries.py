"""One line per ``labkit`` command: what ``labkit --help`` lists without importing any command's
module (each imports numpy, the protocols, OpenCV or numba: ~0.3 s of one core for all of them),
and what each command's own parser shows beside its name."""

from __future__ import annotations

COMMAND_SUMMARIES: dict[str, str] = {
    "demo": "run the Fig. 5.25 sweep on the emulated rig (about 10 s)",
    "ports": "list attached serial ports and cameras, with rig-file URLs",
    "probe": "check that a device talks: identify it and print N readings as JSON lines",
    "emulate": "serve a rig's emulated devices on /dev/pts/N",
    "run": "run a measurement protocol on a rig (speed-sweep, spin-critical, cone-sweep, strobe-sweep)",
    "replay": "re-run a session against its cassettes and check its results",
    "analyse": "analyse laser-trace or stroboscope video",
    "synth": "synthetic laser-screen and stroboscope footage with ground truth",
    "fit": "fit data against the PFR model (Eq. 5.24, 5.81, 5.85, 6.13, 6.37)",
    "simulate": "simulate a scene (rigid magnetic bodies, rotators, fields)",
    "bench": "benchmarks (ratios measured in one run)",
    "reproduce": "reproduce the paper's numbers and compare",
    "report": "write a report folder (markdown + PNG) for a session or result",
    "sweep": "parameter sweeps (stability maps), local or on a Dask cluster",
    "predict": "predict a rotator/floator pair: bound state, stiffness, speeds",
    "rig": "write a rig-file template (rig new balance my-rig.toml) or check one",
    "twin": "run a rig file's virtual twin and compare recovered with put-in values",
    "shrink": "shrink a session's camera frames for a CI fixture; results recomputed",
}
