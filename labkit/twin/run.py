"""``labkit twin``: the Fig. 5.25, Fig. 6.18 and cone-sweep protocols on the model plant of a
rig file, rendered footage, then the fits, compared with what went in (docs/explanation/twin.md)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from labkit.emulators.break_up import break_up
from labkit.emulators.twin_model import TwinParams, missing_from_rig, params_from_rig
from labkit.twin.protocol_run import run_protocol
from labkit.twin.recovery import break_phi_from_c, compare, fit_gap, fit_moment_product, interval_95
from labkit.twin.rigtext import write_twin_rig

#: speed-sweep plan of the twin (the demo's)
SWEEP_SETS = ["speeds_rpm=6000:20000:1000", "record_s=2.0"]


def balance_rows(user_rig: Path, params: TwinParams, work: Path, seed: int) -> tuple[list[dict], dict]:
    """Fig. 5.25: the speed sweep, m_R m_F and the gap recovered from it."""
    rig_file = write_twin_rig(user_rig, "fig525", work / "rigs")
    outcome = run_protocol(rig_file, "speed-sweep", SWEEP_SETS, work / "sessions", seed)
    points = outcome.results["points"]
    rows = [compare("fig5.25", "moment_product", params.moment_product,
                    fit_moment_product(params, points), "A^2 m^4"),
            compare("fig5.25", "gap", params.gap_m, fit_gap(params, points), "mm", 1e3)]
    return rows, {"session": str(outcome.session), "points": points}


def spin_plan(params: TwinParams) -> list[str]:
    """spin-critical plan: from 5 % above the model's lowest trapping speed, +10 % per run."""
    from labkit.emulators.rig_plant import SpinCriticalLaw
    from labkit.units import rad_s_to_rpm
    w0 = SpinCriticalLaw(c=break_up(params).c).min_trap_speed()
    start = rad_s_to_rpm(1.05 * w0)
    return [f"start_rpm={start:.0f}", f"stop_rpm={min(1.8 * start, 15000):.0f}", "step_pct=10",
            "max_trials=3"]


def spin_rows(user_rig: Path, params: TwinParams, work: Path, seed: int) -> tuple[list[dict], dict]:
    """Fig. 6.18: the spin-critical protocol; C of Eq. 6.37 and the break-up cone angle."""
    rig_file = write_twin_rig(user_rig, "fig618", work / "rigs")
    outcome = run_protocol(rig_file, "spin-critical", spin_plan(params), work / "sessions", seed)
    c_fit = outcome.results["fit"]["params"]["C"]
    n = outcome.results["fit"].get("n", len(outcome.results["points"]))
    c = interval_95(c_fit["value"], c_fit["stderr"], n)
    put_in = break_up(params)
    rows = [compare("fig6.18", "C", put_in.c, c, "rad^2/s^2"),
            compare("fig6.18", "break_phi", put_in.phi, break_phi_from_c(params, c), "rad")]
    return rows, {"session": str(outcome.session), "points": outcome.results["points"]}


#: what each part does, said as it starts (``labkit twin`` prints them on stderr)
PART_WORDS = {
    "balance": "Fig. 5.25: the speed sweep (15 speeds) on the model plant, then the fits",
    "spin": "Fig. 6.18: the spin-critical protocol on the model plant, then the Eq. 6.37 fit",
    "footage": "footage: rendering and analysing 4 laser-trace and 4 stroboscope clips",
    "camera": "cone-sweep: the emulated camera films the laser trace at 6 speeds, then the Eq. 5.24 fit",
}


def run_twin(rig_path: str | Path, work: Path, seed: int = 0,
             parts: tuple[str, ...] = ("balance", "spin", "footage", "camera"),
             say: Callable[[str], None] | None = None) -> dict:
    """Every twin row for the rig file ``rig_path``; sessions and rigs go under ``work``;
    ``say`` is told each part as it starts."""
    from labkit.rig import load_rig
    rig = load_rig(rig_path)
    user_rig = Path(rig.path)
    params = params_from_rig(rig)
    rows: list[dict] = []
    runs: dict[str, Any] = {}
    chosen = [p for p in ("balance", "spin", "footage", "camera") if p in parts]
    for n, part in enumerate(chosen, start=1):
        if say is not None:
            say(f"part {n} of {len(chosen)}, {PART_WORDS[part]}")
        if part == "balance":
            r, runs["fig5.25"] = balance_rows(user_rig, params, work, seed)
        elif part == "spin":
            r, runs["fig6.18"] = spin_rows(user_rig, params, work, seed)
        elif part == "footage":
            from labkit.twin.footage import footage_rows
            r, runs["footage"] = footage_rows(params, work, seed)
        else:
            from labkit.twin.camera import camera_rows
            r, runs["camera"] = camera_rows(user_rig, params, work, seed)
        rows += r
    return {"rig": str(user_rig), "seed": seed, "params": params.__dict__,
            "defaults_used_for": missing_from_rig(rig), "rows": rows, "runs": runs}
