"""A sweep on real Dask worker processes stores exactly the in-process rows (issue 28).

Every point is integrated on its own by the same compiled kernel whatever the chunk it rides
in, so on one machine the rows are equal to the last bit: no tolerance. The workers are
``dask worker`` processes behind a ``dask scheduler`` on loopback (what ``labkit bench sweep``
starts), so the rows cross the network as they do on a lab cluster (one pickled blob per task).
"""

from __future__ import annotations

import pytest

from labkit.numerics import stability_map
from labkit.numerics.sweep import load_store, run_sweep

CYCLES = 20


@pytest.mark.timeout(120)
def test_dask_workers_store_the_in_process_rows(tmp_path):
    pytest.importorskip("distributed")
    from labkit.cli.bench_sweep import QUIET_DASK, LoopbackCluster

    points = stability_map.map_points([0.0, 0.1, 0.25, 0.4, 0.6])  # 55 points, both verdicts
    evaluate = stability_map.Evaluator(CYCLES)
    local = run_sweep(points, evaluate, store=tmp_path / "local.jsonl", chunk=len(points), progress=False)
    with LoopbackCluster(2, 60.0, QUIET_DASK) as cluster:
        remote = run_sweep(points, evaluate, store=tmp_path / "dask.jsonl", chunk=4,
                           scheduler=cluster.address, timeout_s=60.0, progress=False)
    assert remote.computed == len(points) == len(local.results)
    assert {r["verdict"] for r in local.results} == {"stable", "unstable"}
    stored_local, stored_dask = load_store(tmp_path / "local.jsonl"), load_store(tmp_path / "dask.jsonl")
    assert len(stored_dask) == len(points)
    assert stored_dask == stored_local
    assert remote.results == local.results  # and returned in the points' order
    lines = (tmp_path / "dask.jsonl").read_text().splitlines()
    assert len(lines) == len(points)  # one line per point, none written twice
