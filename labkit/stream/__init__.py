"""Every rerun call of labkit lives in this package (ARCHITECTURE: `stream`).

Only the CLI and sinks import it; the library never does. Entity paths and timelines are
documented in docs/streams.md. The rerun API churns, so this is the one place to change
when it moves (rerun-sdk is pinned to 0.41.x in pyproject.toml).
"""

from labkit.stream.core import RerunSpec, add_rerun_argument, open_stream, parse_rerun_spec
from labkit.stream.run import run_sink

__all__ = ["RerunSpec", "add_rerun_argument", "open_stream", "parse_rerun_spec", "run_sink"]
