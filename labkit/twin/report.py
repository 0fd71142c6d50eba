"""The twin's report: one markdown table and one JSON document of measured against put-in."""

from __future__ import annotations

import json
from pathlib import Path


def _g(x: float) -> str:
    return f"{x:.6g}"


def markdown(result: dict) -> str:
    """The report as markdown: the rig, then one row per recovered parameter."""
    lines = [f"# labkit twin: {result['rig']}", "",
             f"seed {result['seed']}; model plant built from the rig file's magnets and geometry "
             "(docs/explanation/twin.md).", ""]
    if result["defaults_used_for"]:
        lines += [f"The rig file lacks {', '.join(result['defaults_used_for'])}: the shipped emulated "
                  "rig's values stand in.", ""]
    lines += ["| parameter | unit | put in | recovered | 95 % interval | residual | rel. diff | ok |",
              "|---|---|---|---|---|---|---|---|"]
    for r in result["rows"]:
        lo, hi = r["ci95"]
        lines.append(f"| {r['name']} | {r['unit']} | {_g(r['put_in'])} | {_g(r['recovered'])} | "
                     f"[{_g(lo)}, {_g(hi)}] | {_g(r['residual'])} | {r['rel_diff']:+.2e} | "
                     f"{'yes' if r['ok'] else 'NO'} |")
    bad = [r["name"] for r in result["rows"] if not r["ok"]]
    verdict = ("every put-in value lies inside its 95 % interval." if not bad else
               f"{len(bad)} put-in value(s) outside their 95 % interval: {', '.join(bad)}.")
    lines += ["", "Verdict: " + verdict]
    for name, run in result["runs"].items():
        if isinstance(run, dict) and run.get("session"):
            lines.append(f"- {name} session: {run['session']}")
        if isinstance(run, dict) and run.get("largest_point_rel_diff") is not None:
            lines.append(f"- {name}: every ok point's cone angle within "
                         f"{run['largest_point_rel_diff']:.2e} of the model's at its speed")
    return "\n".join(lines) + "\n"


def write_report(result: dict, out: Path) -> tuple[Path, Path]:
    """Write ``out/twin-report.md`` and ``out/twin-report.json``; return their paths."""
    out.mkdir(parents=True, exist_ok=True)
    md, js = out / "twin-report.md", out / "twin-report.json"
    md.write_text(markdown(result))
    runs = {k: {kk: vv for kk, vv in v.items() if kk != "points"} if isinstance(v, dict) else v
            for k, v in result["runs"].items()}
    slim = {**result, "runs": runs}
    js.write_text(json.dumps(slim, indent=2, default=str) + "\n")
    return md, js
