"""Parameter sweeps: batched on one machine or on a Dask cluster, with progress, resumable.

A sweep is a list of parameter points (plain dicts) and an ``evaluate`` function that takes a
*chunk* of points and returns one result dict per point (a module-level function, so that a
Dask worker can import it). Points are keyed by a hash of their parameters; every finished
chunk is appended to a JSON-lines store at once, so an interrupted sweep resumes from what is
on disk (a torn last line is ignored and its points are run again).

Where the chunks run:

* by default in this process, one chunk after the other
(docs/explanation/numerics-notes.md#one-process-by-default: the batch kernel is what
  makes a sweep fast; on a quiet 2-core machine a pool of 2 buys about 1.9x);
* ``workers > 1``: a local process pool;
* ``scheduler="tcp://host:8786"``: a ``dask.distributed`` cluster (optional dependency
  ``dask[distributed]``), or the caller's own ``distributed.Client``, left open (a notebook that
  holds one saves the connection and its close: about 18 ms per sweep on loopback); a scheduler
  that does not answer within ``timeout_s`` is a clear :class:`SweepError`, not a hang. A large
  ``evaluate`` is sent to every worker once (``Client.scatter(..., broadcast=True)``), a small
  one rides in each task (:func:`_shared`), and a task takes its points and returns its rows as
  one pickled blob each (:func:`_evaluate_packed`, docs/decisions/0038-dask-results-as-one-blob.md).

``chunk=None`` (the default) sizes the chunks from the pending points and the slots that run
them (worker threads of the cluster, pool processes): about ``TASKS_PER_SLOT`` tasks per slot,
each taking every n-th point (:func:`interleaved_chunks`), so that the slots finish together,
and at least ``MIN_CHUNK`` points, so that a task's
scheduling round trip is small against its work. Dask queues root tasks on its scheduler and
hands a worker about one at a time: with 16-point tasks of ~45 ms its workers waited for a
round trip between tasks and a 16-worker cluster ran at half the speed of a local pool
(docs/how-to/run-a-stability-sweep.md, *Sweeps on a cluster*).
"""

from __future__ import annotations

import hashlib
import json
import math
import pickle
from collections.abc import Callable, Iterable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from labkit.numerics.checks import NumericsError

Evaluate = Callable[[list[dict]], list[dict]]


TASKS_PER_SLOT = 4  # tasks per worker slot when the chunks are sized automatically
MIN_CHUNK = 4  # points per task at least, when sized automatically


def auto_chunk(pending: int, slots: int, max_chunk: int | None = None) -> int:
    """Points per task for ``pending`` points on ``slots`` parallel slots (module docstring);
    never above ``max_chunk`` (a memory limit per task, e.g. ``stability_map.check_chunk``)."""
    size = max(MIN_CHUNK, math.ceil(pending / max(1, slots * TASKS_PER_SLOT)))
    return max(1, min(size, max_chunk) if max_chunk is not None else size)


def interleaved_chunks(pending: list, chunk: int) -> list[list]:
    """``pending`` cut into ``ceil(len / chunk)`` tasks of at most ``chunk`` points, task ``i``
    taking every n-th point from the ``i``-th on. Neighbouring points of a map cost alike
    (one configuration, close ratios), so contiguous tasks differ in cost by up to 10 % (Table
    5.3's map: 0.79-0.87 s per 413-point task); interleaved ones hold the same mix of the map and
    differ by 0.6 %, so the slots finish together. An interrupted sweep leaves a coarse version
    of the whole map in its store, not a finished first part."""
    n = math.ceil(len(pending) / max(1, chunk)) if pending else 0
    return [pending[i::n] for i in range(n)]


class SweepError(NumericsError):
    """A sweep cannot run as asked (scheduler unreachable, unreadable store, ...)."""


@dataclass
class SweepResult:
    """Results in the order of the points; how many were computed now and reused from disk."""

    results: list[dict]
    computed: int
    reused: int


def point_key(point: dict) -> str:
    """Stable key of a parameter point (hash of its sorted JSON)."""
    text = json.dumps(point, sort_keys=True, separators=(",", ":"), default=float)
    return hashlib.sha1(text.encode()).hexdigest()[:16]


def load_store(path: Path) -> dict[str, dict]:
    """Results already on disk, by key. A line that does not parse (a write cut short by an
    interruption) is skipped; its points run again."""
    done: dict[str, dict] = {}
    if not path.exists():
        return done
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise SweepError(f"{path}: cannot read the partial results ({exc.strerror})") from None
    for line in raw.splitlines():
        try:
            row = json.loads(line.decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError, RecursionError):
            continue
        if isinstance(row, dict) and "key" in row:
            done[row["key"]] = row
    return done


def _append(path: Path | None, rows: Iterable[dict]) -> None:
    if path is None:
        return
    with path.open("a") as fh:
        for row in rows:
            fh.write(json.dumps(row, default=_jsonable) + "\n")
        fh.flush()


def _jsonable(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return str(x)


def _clean_nan(row: dict) -> dict:
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in row.items()}


def _evaluate_keyed(evaluate: Evaluate, chunk: list[tuple[str, dict]]) -> list[dict]:
    """Run ``evaluate`` on a chunk and tag each result with its point's key and parameters."""
    results = evaluate([p for _, p in chunk])
    if len(results) != len(chunk):
        raise SweepError(f"evaluate returned {len(results)} results for {len(chunk)} points")
    return [_clean_nan({"key": k, **p, **r}) for (k, p), r in zip(chunk, results, strict=True)]


def _evaluate_packed(evaluate: Evaluate, chunk: bytes) -> bytes:
    """:func:`_evaluate_keyed` on a pickled chunk, its rows pickled into one blob: a Dask task.

    Both ways one ``bytes`` object, for the same reason. The scheduler unpickles every task it is
    sent and pickles it again for its worker: a chunk as a list of point dicts cost it 0.12 CPU s
    per 16 500-point map, on the cores the workers compute on, where a blob is copied as it is.
    Dask serialises a returned list item by item (a pickle call, a dispatch lookup and metrics
    per row, on the worker's event loop, which waits for the GIL the computing thread holds);
    one ``bytes`` object is one frame, sent as it is. The blobs are unpickled by the worker and
    the client, which trust each other as Dask itself does (it unpickles whatever they send)."""
    rows = _evaluate_keyed(evaluate, pickle.loads(chunk))
    return pickle.dumps(rows, protocol=pickle.HIGHEST_PROTOCOL)


def connect(scheduler: str, timeout_s: float = 10.0):
    """A ``distributed.Client`` for ``scheduler``; SweepError if it does not answer."""
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - optional dependency
        raise SweepError(
            "a scheduler address needs dask.distributed: pip install 'labkit[cluster]' (dask[distributed])"
        ) from None
    try:
        return Client(scheduler, timeout=f"{timeout_s}s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise SweepError(
            f"Dask scheduler {scheduler} did not answer within {timeout_s:g} s ({type(exc).__name__}): "
            "check the address and that `dask scheduler` runs there, or leave out --scheduler to "
            "run on this machine"
        ) from None


def run_sweep(
    points: list[dict],
    evaluate: Evaluate,
    store: str | Path | None = None,
    chunk: int | None = None,
    workers: int = 1,
    scheduler: str | Any | None = None,
    timeout_s: float = 10.0,
    progress: bool = True,
    description: str = "sweep",
    limit: int | None = None,
    max_chunk: int | None = None,
) -> SweepResult:
    """Run ``evaluate`` over ``points`` in chunks; see the module docstring.

    ``chunk`` points per task (``None``: :func:`auto_chunk`, at most ``max_chunk``). ``limit``
    stops after that many new points (what an interruption leaves behind; the results then hold
    only the finished points).
    """
    path = Path(store) if store is not None else None
    if path is not None and path.parent and not path.parent.exists():
        raise SweepError(f"{path}: the folder for the partial results does not exist")
    done = load_store(path) if path is not None else {}
    keyed = [(point_key(p), p) for p in points]
    pending = [(k, p) for k, p in keyed if k not in done]
    if limit is not None:
        pending = pending[:limit]
    reused = len(keyed) - len([1 for k, _ in keyed if k not in done])
    new: dict[str, dict] = {}
    held = scheduler is not None and not isinstance(scheduler, str)  # the caller's own Client
    client = None
    if scheduler is not None and pending:
        client = scheduler if held else connect(scheduler, timeout_s)
    if chunk is None:
        chunk = auto_chunk(len(pending), _slots(client, workers), max_chunk)
    chunks = interleaved_chunks(pending, chunk)

    bar = _progress(progress, description, len(keyed), reused)
    try:
        for rows in _execute(chunks, evaluate, workers, client):
            _append(path, rows)
            for row in rows:
                new[row["key"]] = row
            if bar is not None:
                bar[0].advance(bar[1], len(rows))
    finally:
        if bar is not None:
            bar[0].stop()
        if client is not None and not held:
            client.close()
    merged = {**done, **new}
    results = [merged[k] for k, _ in keyed if k in merged]
    return SweepResult(results, len(new), reused)


def _progress(enabled: bool, description: str, total: int, completed: int):
    if not enabled:
        return None
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    prog = Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
        console=Console(stderr=True),
    )
    prog.start()
    task = prog.add_task(description, total=total, completed=completed)
    return prog, task


def _slots(client, workers: int) -> int:
    """How many tasks run at once: the cluster's worker threads, else the local processes."""
    if client is not None:
        threads = client.nthreads()
        return max(1, sum(threads.values())) if threads else 1
    return max(1, workers)


SCATTER_BYTES = 64 * 1024  # an ``evaluate`` pickled larger than this is scattered, not sent per task


def _shared(client, evaluate: Evaluate):
    """``evaluate`` as the tasks take it: sent to every worker once
    (``Client.scatter(..., broadcast=True)``) when its pickle is over :data:`SCATTER_BYTES` or
    plain pickle cannot size it (a closure: Dask's cloudpickle still sends it), else as it is,
    inside each task. A scatter is a round trip to the scheduler and every worker before the
    first task starts: on loopback it cost 20 ms of CPU and 6 ms per sweep for an ``evaluate``
    of a hundred bytes, which every task carries for nothing."""
    try:
        small = len(pickle.dumps(evaluate, protocol=pickle.HIGHEST_PROTOCOL)) <= SCATTER_BYTES
    except (pickle.PicklingError, TypeError, AttributeError):
        small = False
    return evaluate if small else client.scatter(evaluate, broadcast=True, hash=False)


def _execute(chunks, evaluate: Evaluate, workers: int, client):
    """Yield the rows of each finished chunk (in completion order)."""
    if not chunks:
        return
    if client is not None:
        from distributed import as_completed as dask_completed

        shared = _shared(client, evaluate)
        blobs = [pickle.dumps(c, protocol=pickle.HIGHEST_PROTOCOL) for c in chunks]
        futures = client.map(_evaluate_packed, [shared] * len(blobs), blobs, pure=False)
        # results travel with the completion notice (one gather per batch of finished tasks, not
        # one round trip per task), and each future is dropped once its rows are out
        for fut, blob in dask_completed(futures, with_results=True, loop=client.loop):
            fut.release()
            yield pickle.loads(blob)
        return
    if workers > 1:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            futures = [pool.submit(_evaluate_keyed, evaluate, c) for c in chunks]
            for fut in as_completed(futures):
                yield fut.result()
        return
    for c in chunks:
        yield _evaluate_keyed(evaluate, c)
