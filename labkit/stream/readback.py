"""Reading an .rrd back (tests, reports): entity paths and columns, via ``rerun.chunk.RrdReader``.

docs/explanation/rerun-notes.md#reading-a-recording-back: the old ``rerun.dataframe`` module is gone in 0.41.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any


def entity_paths(path: str | Path, include_static: bool = True) -> set[str]:
    """Every entity path with data in the recording at ``path`` (blueprint entities excluded)."""
    from rerun.chunk import RrdReader

    out: set[str] = set()
    for chunk in RrdReader(str(path)).stream():
        batch = chunk.to_record_batch()
        meta = batch.schema.metadata or {}
        entity = meta.get(b"rerun:entity_path") or meta.get(b"rerun.entity_path")
        if entity is None:
            continue
        name = entity.decode()
        if not include_static and chunk_is_static(batch):
            continue
        if not name.startswith("/__"):
            out.add(name)
    return out


def chunk_is_static(batch: Any) -> bool:
    """A static chunk has no timeline column (columns are ``RowId`` and ``Archetype:field``)."""
    return not any(":" not in name and not name.startswith("rerun.") for name in batch.schema.names)


def column(path: str | Path, entity: str, component: str, timeline: str) -> tuple[list, list]:
    """``(times, values)`` of one component of one entity along ``timeline`` (sorted)."""
    import pyarrow as pa
    from rerun.chunk import RrdReader

    chunks = list(RrdReader(str(path)).stream().filter(content=entity, is_static=False))
    batches = [c.to_record_batch() for c in chunks]
    batches = [b.select([timeline, component]) for b in batches
               if timeline in b.schema.names and component in b.schema.names]
    if not batches:
        return [], []
    # rows logged on other timelines too have more columns: keep the two asked for
    table = pa.Table.from_batches(batches).sort_by(timeline)
    return table.column(timeline).to_pylist(), table.column(component).to_pylist()
