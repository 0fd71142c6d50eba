"""The sink ``labkit simulate --rerun SPEC`` looks for: ``stream_result(result, spec)``."""

from __future__ import annotations

from typing import Any

from labkit.stream.sim import stream_sim_result


def stream_result(result: Any, spec: str) -> None:
    stream_sim_result(spec, result)
