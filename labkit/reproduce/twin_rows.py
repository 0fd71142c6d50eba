"""``twin/...``: labkit's measurement chain recovers what went into the model plant
(docs/explanation/twin.md).

The bundled ``emulated-fig525`` rig's magnets go into the model plant; the Fig. 5.25 sweep,
the Fig. 6.18 spin-critical protocol and the footage analyses run on it (seed 0, virtual
clock) and their fits come back. ``paper`` is the put-in value, ``labkit`` the recovered one;
a row is ok when the put-in value lies inside the fit's 95 % interval and within 2 % of it.
``--quick`` runs the Fig. 5.25 sweep only.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from labkit.reproduce import Row

REL_TOL = 0.02


def to_row(r: dict) -> Row:
    lo, hi = r["ci95"]
    ok = bool(r["ok"] and abs(r["rel_diff"]) <= REL_TOL)
    note = f"{r['unit']}; 95 % interval [{lo:.6g}, {hi:.6g}], n = {r['n']}; seed 0"
    return Row(r["name"], r["param"], r["put_in"], r["recovered"], r["rel_diff"], ok, note)


def rows(quick: bool = False, prefix: str = "") -> list[Row]:
    from labkit.rig import bundled_rig_path
    from labkit.twin.run import run_twin
    with tempfile.TemporaryDirectory(prefix="labkit-twin-") as work:
        parts = ("balance",) if quick else ("balance", "spin", "footage")   # --quick: seconds
        result = run_twin(bundled_rig_path("emulated-fig525"), Path(work), seed=0,  # type: ignore[arg-type]
                          parts=parts)
    return [to_row(r) for r in result["rows"]]
