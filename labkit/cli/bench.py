"""``labkit bench {io,sim,...}``: benchmarks that print ratios measured in one run.

Each benchmark lives in ``labkit.cli.bench_<name>`` with ``register(subparsers)``.
"""

from __future__ import annotations

import argparse
import importlib

from labkit.cli.summaries import COMMAND_SUMMARIES

BENCHES = ["io", "sim", "vision", "run", "sweep", "camera"]


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("bench", help=COMMAND_SUMMARIES["bench"])
    benches = parser.add_subparsers(dest="bench", metavar="BENCH")
    for name in BENCHES:
        module_name = f"labkit.cli.bench_{name}"
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name == module_name:
                continue
            raise
        module.register(benches)
    parser.set_defaults(func=lambda args: parser.print_help() or 1)
