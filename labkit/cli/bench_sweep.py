"""``labkit bench sweep``: how a stability map scales, in this process, on a local process pool
and on a real Dask cluster on this machine.

Starts ``dask scheduler`` and N single-threaded ``dask worker`` processes on 127.0.0.1 (what a
lab starts on its own machines; nothing listens beyond loopback), runs the same Table 5.3 map
in process, on a pool of N processes and on the N Dask workers, and prints each one's speed-up
over the in-process map, measured in one run. Every engine is warmed first (numba's compiled
kernels loaded in every process) so that the table compares the sweep, not the start-up; each
timed region is one ``run_sweep`` call as a user makes it (the pool's processes started, the
Dask client connected and ``evaluate`` scattered inside it).

Beside the wall times the table gives the CPU seconds each engine's processes used (the pool's
processes; Dask's workers, scheduler and this process's client), which a loaded machine does
not blur: the work is the same, what Dask adds is its processes' own housekeeping. Dask's
event loops check themselves every 20 ms, and each worker samples its memory every 100 ms and
its threads every 10 ms: ~1.5-2 % of a core per process, idle or not, which on two shared cores
is the whole gap to the pool. The cluster is started with :data:`QUIET_DASK` (those checks
every few seconds, the profiler off), the settings the docs give for a compute cluster;
``--dask-defaults`` starts it with Dask's own.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

LOOPBACK = "127.0.0.1"
#: Dask settings of the benchmark's cluster (and the docs' advice for a compute cluster): the
#: event loop's self-check, the system and memory monitors every few seconds instead of every
#: 20 / 500 / 100 ms, and no statistical profiler (a thread sampling every 10 ms). Nothing the
#: sweep uses: the dashboard's plots, memory spilling (a sweep's tasks hold little) and the
#: warning of a blocked event loop react later.
QUIET_DASK = {
    "distributed.admin.tick.interval": "2s",
    "distributed.admin.system-monitor.interval": "5s",
    "distributed.worker.memory.monitor-interval": "5s",
    "distributed.worker.profile.enabled": "False",
}


def dask_env(config: dict[str, str]) -> dict[str, str]:
    """Dask's environment variables for ``config`` (``DASK_`` + the key upper-cased, ``.`` as
    ``__``, ``-`` as ``_``)."""
    return {"DASK_" + key.upper().replace(".", "__").replace("-", "_"): value
            for key, value in config.items()}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("sweep", help="stability-map speed-up: in process, process pool, Dask on loopback")
    p.add_argument("--ratios", type=int, default=300,
                   help="tau_S/tau_C ratios of the map, 11 points each (default 300: 3300 points)")
    p.add_argument("--cycles", type=int, default=100, help="drive periods per point (default 100)")
    p.add_argument("--workers", default="1,2", help="worker counts to measure (default 1,2)")
    p.add_argument("--timeout", type=float, default=60.0, help="seconds to wait for the cluster to start")
    p.add_argument("--dask-defaults", action="store_true",
                   help="start the Dask cluster with Dask's default monitor intervals, not QUIET_DASK")
    p.set_defaults(func=main)


def _dask(*args: str) -> list[str]:
    return [sys.executable, "-m", "distributed.cli.dask_" + args[0], *args[1:]]


class LoopbackCluster:
    """``dask scheduler`` and ``workers`` single-threaded ``dask worker`` processes on loopback."""

    def __init__(self, workers: int, timeout_s: float, config: dict[str, str] | None = None) -> None:
        self.workers, self.timeout_s = workers, timeout_s
        self.env = {**os.environ, **dask_env(config or {})}
        self.folder = tempfile.TemporaryDirectory(prefix="labkit-bench-sweep-")
        self.procs: list[subprocess.Popen] = []
        self.address = ""

    def __enter__(self) -> LoopbackCluster:
        info = Path(self.folder.name) / "scheduler.json"
        self.procs.append(self._start(_dask("scheduler", "--host", LOOPBACK, "--port", "0",
                                            "--no-dashboard", "--scheduler-file", str(info)), self.env))
        deadline = time.monotonic() + self.timeout_s
        while not info.exists() or not info.read_text().strip():
            if time.monotonic() > deadline or self.procs[0].poll() is not None:
                self.__exit__()
                raise RuntimeError("the Dask scheduler did not start")
            time.sleep(0.1)
        self.address = json.loads(info.read_text())["address"]
        env = {**self.env, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
        for _ in range(self.workers):
            self.procs.append(self._start(
                _dask("worker", self.address, "--nthreads", "1", "--nworkers", "1", "--host", LOOPBACK,
                      "--no-dashboard", "--no-nanny"), env))
        return self

    @staticmethod
    def _start(argv: list[str], env: dict[str, str]) -> subprocess.Popen:
        return subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    def wait_for_workers(self, client) -> None:
        client.wait_for_workers(self.workers, timeout=self.timeout_s)

    def __exit__(self, *exc: object) -> None:
        for proc in reversed(self.procs):
            if proc.poll() is None:
                proc.terminate()
        for proc in self.procs:
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        self.folder.cleanup()


def _cpu_s(pids: list[int]) -> float:
    """CPU seconds (user + system) the processes ``pids`` used so far."""
    import psutil  # a dependency of dask.distributed

    total = 0.0
    for pid in pids:
        times = psutil.Process(pid).cpu_times()
        total += times.user + times.system
    return total


def _children_cpu_s() -> float:
    """CPU seconds of this process's children that have ended (the pool's processes)."""
    import resource

    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _timed(fn, cpu=None) -> tuple[float, float]:
    """(wall seconds, CPU seconds ``cpu()`` grew by) of ``fn()``."""
    cpu = cpu or (lambda: 0.0)
    before, start = cpu(), time.perf_counter()
    fn()
    return time.perf_counter() - start, cpu() - before


def main(args: argparse.Namespace) -> int:
    import dask
    from distributed import Client

    from labkit.numerics import stability_map
    from labkit.numerics.sweep import run_sweep

    counts = [int(n) for n in args.workers.split(",") if n.strip()]
    ratios = [0.6 * i / max(1, args.ratios - 1) for i in range(args.ratios)]
    points = stability_map.map_points(ratios)
    evaluate = stability_map.Evaluator(args.cycles)
    config = {} if args.dask_defaults else QUIET_DASK
    print(f"Table 5.3 map: {len(points)} points x {args.cycles} cycles, {os.cpu_count()} cores; "
          f"Dask {'defaults' if args.dask_defaults else 'QUIET_DASK (labkit bench sweep --help)'}")
    run_sweep(points[:8], evaluate, progress=False)  # numba's kernels compiled / loaded here
    me = [os.getpid()]
    serial, serial_cpu = _timed(lambda: run_sweep(points, evaluate, progress=False), lambda: _cpu_s(me))
    print(f"in process: {serial:.2f} s (1.00x), {serial_cpu:.2f} CPU s")
    print("workers | pool | Dask, 16-point tasks | Dask, sized tasks | Dask sized / pool | "
          "CPU s: pool, Dask sized (workers + scheduler + client)")
    with dask.config.set({k: (v != "False") if v in ("True", "False") else v for k, v in config.items()}):
        for n in counts:
            pool, pool_cpu = _timed(lambda n=n: run_sweep(points, evaluate, workers=n, progress=False),
                                    lambda: _children_cpu_s() + _cpu_s(me))
            with LoopbackCluster(n, args.timeout, config) as cluster:
                with Client(cluster.address, set_as_default=False) as client:
                    cluster.wait_for_workers(client)
                    client.run(lambda: run_sweep(points[:8], evaluate, progress=False) and None)  # warm
                fixed, _ = _timed(lambda: run_sweep(points, evaluate, chunk=16, scheduler=cluster.address,
                                                    progress=False))
                pids = [proc.pid for proc in cluster.procs] + me
                sized, sized_cpu = _timed(lambda: run_sweep(points, evaluate, scheduler=cluster.address,
                                                            progress=False), lambda pids=pids: _cpu_s(pids))
            print(f"{n:7d} | {serial / pool:4.2f}x | {serial / fixed:19.2f}x | {serial / sized:16.2f}x | "
                  f"{pool / sized:17.2f} | {pool_cpu:.2f}, {sized_cpu:.2f}")
    return 0
