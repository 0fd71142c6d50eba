"""Where a Dask sweep's CPU goes, per process and per thread, beside a local pool's (issue 28;
docs/how-to/run-a-stability-sweep.md, *What Dask costs beyond the pool*).

Starts the benchmark's loopback cluster (``dask scheduler`` and N single-threaded ``dask
worker`` processes with ``QUIET_DASK``, labkit/cli/bench_sweep.py), then runs the 3 300-point
Table 5.3 map ``--repeats`` times on a pool of N and on the cluster, interleaved, and prints
the CPU seconds of: the pool (its processes and this one), the Dask workers' computing threads
and their event loops, the scheduler, and the client (this process: the sweep's own hashing
and store writes, the same as for the pool, plus Dask's client). Ends with each Dask process's
CPU per second while idle (the part of Dask's cost that grows with the sweep's duration).

    python analysis/sweep_dask_cpu_split.py                 # 2 workers, 3 repeats (~1 min quiet)
    python analysis/sweep_dask_cpu_split.py --workers 2 --repeats 5 --ratios 1500
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import tempfile
import time
from pathlib import Path

import psutil
from distributed import Client

from labkit.cli.bench_sweep import QUIET_DASK, LoopbackCluster
from labkit.numerics import stability_map
from labkit.numerics.sweep import run_sweep


def _cpu(proc: psutil.Process) -> float:
    times = proc.cpu_times()
    return times.user + times.system


def _threads(proc: psutil.Process) -> dict[int, float]:
    return {t.id: t.user_time + t.system_time for t in proc.threads()}


def _children() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _compute_thread_ids(client: Client) -> set[int]:
    """Native ids of the workers' executor threads (the ones that run the tasks)."""
    def ids() -> list[int]:
        import threading

        return [t.native_id for t in threading.enumerate() if t.name.startswith("Dask-Default-Threads")]

    return {tid for found in client.run(ids).values() for tid in found}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--ratios", type=int, default=300, help="ratios of the map, 11 points each")
    parser.add_argument("--cycles", type=int, default=100)
    args = parser.parse_args()
    points = stability_map.map_points([0.6 * i / max(1, args.ratios - 1) for i in range(args.ratios)])
    evaluate = stability_map.Evaluator(args.cycles)
    run_sweep(points[:8], evaluate, progress=False)
    me = psutil.Process()
    rows = []
    with LoopbackCluster(args.workers, 60.0, QUIET_DASK) as cluster, \
            tempfile.TemporaryDirectory() as folder:
        store = Path(folder) / "store.jsonl"
        with Client(cluster.address, set_as_default=False) as client:
            cluster.wait_for_workers(client)
            client.run(lambda: run_sweep(points[:8], evaluate, progress=False) and None)
        run_sweep(points[:100], evaluate, scheduler=cluster.address, progress=False)  # threads started
        with Client(cluster.address, set_as_default=False) as client:
            compute = _compute_thread_ids(client)
        scheduler, *workers = (psutil.Process(p.pid) for p in cluster.procs)
        for _ in range(args.repeats):
            load = os.getloadavg()[0]
            store.unlink(missing_ok=True)
            mine, kids, start = _cpu(me), _children(), time.perf_counter()
            run_sweep(points, evaluate, workers=args.workers, store=store, progress=False)
            pool_s, pool_cpu = time.perf_counter() - start, _cpu(me) - mine + _children() - kids
            store.unlink(missing_ok=True)
            before = [_threads(w) for w in workers]
            sched, mine, start = _cpu(scheduler), _cpu(me), time.perf_counter()
            run_sweep(points, evaluate, scheduler=cluster.address, store=store, progress=False)
            dask_s = time.perf_counter() - start
            after = [_threads(w) for w in workers]
            spent = [{tid: t - b.get(tid, 0.0) for tid, t in a.items()}
                     for a, b in zip(after, before, strict=True)]
            work = sum(v for s in spent for tid, v in s.items() if tid in compute)
            loops = sum(v for s in spent for tid, v in s.items() if tid not in compute)
            rows.append((pool_cpu, work, loops, _cpu(scheduler) - sched, _cpu(me) - mine))
            print(f"load {load:4.1f}  pool {pool_s:5.2f} s {pool_cpu:.2f} CPU s | "
                  f"Dask {dask_s:5.2f} s: workers "
                  f"computing {work:.2f}, their event loops {loops:.3f}, scheduler {rows[-1][3]:.3f}, "
                  f"client {rows[-1][4]:.3f} CPU s", flush=True)
        med = [statistics.median(r[i] for r in rows) for i in range(5)]
        print(f"median: pool {med[0]:.2f} CPU s; Dask {sum(med[1:]):.2f} = computing {med[1]:.2f} + "
              f"event loops "
              f"{med[2]:.3f} + scheduler {med[3]:.3f} + client {med[4]:.3f}")
        procs = [scheduler, *workers]
        idle = [_cpu(p) for p in procs]
        time.sleep(10)
        rates = ", ".join(f"{(_cpu(p) - c) / 10:.4f}" for p, c in zip(procs, idle, strict=True))
        print(f"idle CPU s per second (scheduler, workers): {rates}")


if __name__ == "__main__":
    main()
