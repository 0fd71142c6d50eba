"""Sweep task sizes (issue 28) and the cluster benchmark's table."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from labkit.cli import main
from labkit.numerics import stability_map
from labkit.numerics.sweep import MIN_CHUNK, TASKS_PER_SLOT, auto_chunk, interleaved_chunks


@given(st.integers(0, 10**6), st.integers(1, 512), st.none() | st.integers(1, 10**4))
def test_auto_chunk_covers_the_slots_and_respects_the_memory_limit(pending, slots, limit):
    size = auto_chunk(pending, slots, limit)
    assert size >= 1
    if limit is not None:
        assert size <= limit
    tasks = math.ceil(pending / size) if pending else 0
    # at most TASKS_PER_SLOT tasks per slot, unless the tasks would be tiny or too large to fit
    assert tasks <= slots * TASKS_PER_SLOT or size in (MIN_CHUNK, limit)


@given(st.integers(0, 3000), st.integers(1, 600))
def test_interleaved_tasks_hold_every_point_once_and_differ_by_at_most_one(pending, chunk):
    points = list(range(pending))
    tasks = interleaved_chunks(points, chunk)
    assert len(tasks) == math.ceil(pending / chunk)
    assert sorted(p for task in tasks for p in task) == points
    assert all(0 < len(task) <= chunk for task in tasks)
    if tasks:
        assert max(map(len, tasks)) - min(map(len, tasks)) <= 1


def test_a_16_worker_map_gets_tasks_of_about_a_sixtyfourth():
    assert auto_chunk(16_500, 16) == math.ceil(16_500 / 64)
    assert auto_chunk(10, 16) == MIN_CHUNK  # a small map is not cut into one-point tasks


def test_the_memory_limit_caps_the_task_size():
    cycles = 4_000_000
    cap = stability_map.max_chunk(cycles)
    stability_map.check_chunk(cap, cycles)  # fits
    with pytest.raises(Exception, match="GiB of samples"):
        stability_map.check_chunk(cap + 1, cycles)


@pytest.mark.timeout(240)
def test_bench_sweep_prints_pool_and_dask_speedups(capsys):
    pytest.importorskip("distributed")
    argv = ["bench", "sweep", "--ratios", "6", "--cycles", "5", "--workers", "1", "--repeats", "2"]
    assert main(argv) == 0  # exit code 1 if a store differs from the in-process one
    out = capsys.readouterr().out
    assert "stored rows: pool and Dask identical to the in-process map" in out
    row = next(line for line in out.splitlines() if line.strip().startswith("1 |"))
    speedups = [float(cell.split()[0].rstrip("x")) for cell in row.split("|")[1:5]]
    assert all(s > 0 for s in speedups)
    low, high = (float(v) for v in row.split("|")[1].split("[")[1].rstrip("] ").split("-"))
    assert low <= speedups[0] <= high  # the pool's median inside its range of 2 repeats
