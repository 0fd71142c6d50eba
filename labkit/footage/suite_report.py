"""Summaries of a robustness-suite run: pass rate per family and difficulty, the confusion table
of pattern kinds (true kind against reported kind), and the verdict counts that matter: cases
outside tolerance whose verdict was ``ok`` (or that carried no verdict at all), and cases labelled
``doubtful`` that were in fact right."""

from __future__ import annotations

from collections import Counter, defaultdict

from labkit.footage.suite import DIFFICULTIES, FAMILIES
from labkit.footage.suite_eval import Outcome, truth_kind


def summarise(outcomes: list[Outcome]) -> dict:
    """Counts as a JSON-ready dict."""
    table: dict[str, dict[str, list[int]]] = defaultdict(lambda: defaultdict(lambda: [0, 0]))
    for o in outcomes:
        for fam in (o.case.family, "all"):
            for d in (o.case.difficulty, "all"):
                cell = table[fam][d]
                cell[0] += int(o.passed)
                cell[1] += 1
    confusion: dict[str, Counter] = defaultdict(Counter)
    for o in outcomes:
        if o.case.family != "strobe":
            confusion[truth_kind(o.case)][o.reported] += 1
    verdicts = Counter(o.verdict or "none" for o in outcomes)
    wrong_ok = [o.case.name for o in outcomes if not o.passed and o.verdict == "ok"]
    wrong_none = [o.case.name for o in outcomes if not o.passed and o.verdict is None]
    doubtful_right = [o.case.name for o in outcomes if o.passed and o.verdict == "doubtful"]
    failures = Counter(f for o in outcomes for f in o.failures)
    return {
        "cases": len(outcomes), "passed": sum(o.passed for o in outcomes),
        "pass_table": {f: {d: list(c) for d, c in row.items()} for f, row in table.items()},
        "confusion": {k: dict(v) for k, v in confusion.items()},
        "verdicts": dict(verdicts), "wrong_but_ok": wrong_ok, "wrong_without_verdict": wrong_none,
        "doubtful_but_right": doubtful_right, "failed_checks": dict(failures),
    }


def _rate(cell: list[int] | None) -> str:
    if not cell or not cell[1]:
        return "-"
    return f"{cell[0]}/{cell[1]} ({100 * cell[0] / cell[1]:.0f}%)"


def format_summary(summary: dict) -> str:
    """The report printed by ``labkit bench vision --suite``."""
    lines = [f"{'family':14s}" + "".join(f"{d:>16s}" for d in (*DIFFICULTIES, "all"))]
    table = summary["pass_table"]
    for fam in (*FAMILIES, "all"):
        if fam in table:
            cells = "".join(f"{_rate(table[fam].get(d)):>16s}" for d in (*DIFFICULTIES, "all"))
            lines.append(f"{fam:14s}{cells}")
    conf = summary["confusion"]
    if conf:
        reported = sorted({r for row in conf.values() for r in row})
        lines += ["", "confusion (rows: true kind, columns: reported kind)",
                  f"{'':16s}" + "".join(f"{r[:14]:>15s}" for r in reported)]
        for kind in sorted(conf):
            lines.append(f"{kind:16s}" + "".join(f"{conf[kind].get(r, 0) or '.':>15}" for r in reported))
    v = summary["verdicts"]
    wrong_ok = summary["wrong_but_ok"]
    named = f"  ({', '.join(wrong_ok[:8])}{' ...' if len(wrong_ok) > 8 else ''})" if wrong_ok else ""
    checks = ", ".join(f"{k} {n}" for k, n in sorted(summary["failed_checks"].items())) or "none"
    lines += ["", "verdicts: " + ", ".join(f"{k} {n}" for k, n in sorted(v.items())),
              f"outside tolerance but verdict ok: {len(wrong_ok)}{named}",
              f"outside tolerance and no verdict given: {len(summary['wrong_without_verdict'])}",
              f"doubtful but right: {len(summary['doubtful_but_right'])}",
              f"failed checks: {checks}"]
    return "\n".join(lines)
