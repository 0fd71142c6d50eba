"""Every rerun call of labkit lives in this package (docs/explanation/architecture.md#one-package-for-rerun).

Only the CLI and sinks import it; the library never does. Entity paths and timelines are
documented in docs/reference/streams.md. The rerun API churns, so this is the one place to change
when it moves (rerun-sdk is pinned to 0.41.x in pyproject.toml).
"""

from labkit.stream.core import RerunSpec, add_rerun_argument, open_stream, parse_rerun_spec


def __getattr__(name: str):
    # run_sink (numpy) is loaded on first use, so a parser that adds --rerun stays light
    if name == "run_sink":
        from labkit.stream.run import run_sink

        return run_sink
    raise AttributeError(f"module 'labkit.stream' has no attribute {name!r}")

__all__ = ["RerunSpec", "add_rerun_argument", "open_stream", "parse_rerun_spec", "run_sink"]
