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
        # a closure plain pickle cannot size goes to the workers by scatter, and gives the same rows
        scattered = run_sweep(points, lambda chunk: evaluate(chunk), chunk=4,
                              scheduler=cluster.address, timeout_s=60.0, progress=False)
        from distributed import Client

        with Client(cluster.address, set_as_default=False) as client:
            held_rows = [run_sweep(points, evaluate, chunk=8, scheduler=client, progress=False).results
                         for _ in range(2)]
            assert client.status == "running"
    assert scattered.results == local.results
    assert held_rows == [local.results, local.results]  # a held client serves two sweeps, left open
    assert remote.computed == len(points) == len(local.results)
    assert {r["verdict"] for r in local.results} == {"stable", "unstable"}
    stored_local, stored_dask = load_store(tmp_path / "local.jsonl"), load_store(tmp_path / "dask.jsonl")
    assert len(stored_dask) == len(points)
    assert stored_dask == stored_local
    assert remote.results == local.results  # and returned in the points' order
    lines = (tmp_path / "dask.jsonl").read_text().splitlines()
    assert len(lines) == len(points)  # one line per point, none written twice


def test_the_batch_kernel_lets_other_threads_run():
    """A worker's event loop (or a second worker thread) runs while a chunk integrates: the
    kernel releases the GIL (ADR 0038). Before, a thread ticking every 2 ms ran 0 times during
    a 0.9 s chunk."""
    import threading
    import time

    from labkit.numerics import kernels

    spec, _ = stability_map.batch_spec(stability_map.map_points([0.1, 0.3])[:16])
    kernels.run_batch_numba(spec, 1, 64, 4)  # compiled / loaded before timing
    ticks: list[float] = []
    done = threading.Event()

    def tick() -> None:
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.002)

    thread = threading.Thread(target=tick)
    thread.start()
    time.sleep(0.02)
    start = time.perf_counter()
    kernels.run_batch_numba(spec, 800, 64, 4)
    end = time.perf_counter()
    done.set()
    thread.join()
    assert end - start > 0.1, "the chunk ran too briefly to tell"
    # away from the Python before and after the compiled loop, where the GIL is free anyway
    inside = [t for t in ticks if start + 0.03 < t < end - 0.03]
    assert inside, f"no other thread ran during a {end - start:.2f} s chunk"
