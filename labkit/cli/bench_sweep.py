"""``labkit bench sweep``: how a stability map scales, in this process, on a local process pool
and on a real Dask cluster on this machine.

Starts ``dask scheduler`` and N single-threaded ``dask worker`` processes on 127.0.0.1 (what a
lab starts on its own machines; nothing listens beyond loopback), runs the same Table 5.3 map
in process, on a pool of N processes and on the N Dask workers, and prints each one's speed-up
over the in-process map, measured in one run. Every engine is warmed first (numba's compiled
kernels loaded in every process, the modules a task's pickle names imported by the scheduler)
so that the table compares the sweep, not the start-up; each
timed region is one ``run_sweep`` call as a user makes it (the pool's processes started, the
Dask client connected inside it), writing its own results store as
``labkit sweep --out`` does. The three engines run interleaved ``--repeats`` times (the order
reversed every other repeat) and the table gives medians and ranges with the load; the command
exits 1 unless the pool's and Dask's stores hold exactly the in-process rows.

Beside the wall times the table gives the CPU seconds each engine's processes used (the pool's
processes; Dask's workers, scheduler and this process's client), which a loaded machine does
not blur: the work is the same, what Dask adds is its processes' own housekeeping. With Dask's
defaults its event loops check themselves every 20 ms, and each worker samples its memory every
100 ms and its threads every 10 ms: ~1.5-2 % of a core per process, idle or not. The cluster is
started with :data:`QUIET_DASK` (those checks every few seconds, the profiler off), the settings
the docs give for a compute cluster; ``--dask-defaults`` starts it with Dask's own.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
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
    p.add_argument("--repeats", type=int, default=3,
                   help="interleaved runs of each engine per worker count (default 3; median and range)")
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


@dataclass
class Repeat:
    """One interleaved repeat for N workers: wall and CPU seconds per engine, the load before."""

    load: float
    serial: tuple[float, float]
    pool: tuple[float, float]
    dask: tuple[float, float]


def _median_range(values: list[float], fmt: str, unit: str = "") -> str:
    """``median[unit] [min-max]`` (just the median for one value)."""
    text = format(statistics.median(values), fmt) + unit
    if len(values) > 1:
        text += f" [{min(values):{fmt}}-{max(values):{fmt}}]"
    return text


def _measure(n: int, points: list[dict], evaluate, cluster: LoopbackCluster, store_dir: Path,
             repeats: int) -> list[Repeat]:
    """``repeats`` runs of the in-process map, a pool of ``n`` and the ``n`` Dask workers,
    interleaved (the order reversed every other repeat, so a change of load hits all three
    alike), each writing its own store as ``labkit sweep --out`` does."""
    from labkit.numerics.sweep import run_sweep

    me = [os.getpid()]
    pids = [proc.pid for proc in cluster.procs] + me

    def engine(name: str):
        kwargs = {"pool": {"workers": n}, "dask": {"scheduler": cluster.address}}.get(name, {})
        cpu = {"serial": lambda: _cpu_s(me), "pool": lambda: _children_cpu_s() + _cpu_s(me),
               "dask": lambda: _cpu_s(pids)}[name]

        def run() -> None:
            store = store_dir / f"{name}-{n}.jsonl"
            store.unlink(missing_ok=True)
            run_sweep(points, evaluate, store=store, progress=False, **kwargs)
        return _timed(run, cpu)

    out = []
    for r in range(repeats):
        load = os.getloadavg()[0]
        order = ["serial", "pool", "dask"] if r % 2 == 0 else ["dask", "pool", "serial"]
        got = {name: engine(name) for name in order}
        out.append(Repeat(load, got["serial"], got["pool"], got["dask"]))
    return out


def _same_rows(store_dir: Path, n: int) -> bool:
    """Whether the Dask and the pool stores hold exactly the in-process rows."""
    from labkit.numerics.sweep import load_store

    serial = load_store(store_dir / f"serial-{n}.jsonl")
    return all(load_store(store_dir / f"{name}-{n}.jsonl") == serial for name in ("pool", "dask"))


def _row(n: int, runs: list[Repeat], fixed16: float) -> str:
    pool = [r.serial[0] / r.pool[0] for r in runs]
    dask = [r.serial[0] / r.dask[0] for r in runs]
    ratio = [r.pool[0] / r.dask[0] for r in runs]
    cpu = [statistics.median(getattr(r, e)[1] for r in runs) for e in ("serial", "pool", "dask")]
    serial = statistics.median(r.serial[0] for r in runs)
    return (f"{n:7d} | {_median_range(pool, '.2f', 'x')} | {serial / fixed16:.2f}x | "
            f"{_median_range(dask, '.2f', 'x')} | "
            f"{_median_range(ratio, '.2f')} | {cpu[0]:.2f}, {cpu[1]:.2f}, {cpu[2]:.2f} | "
            f"{serial:.2f} s | {_median_range([r.load for r in runs], '.1f')}")


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
          f"Dask {'defaults' if args.dask_defaults else 'QUIET_DASK (labkit bench sweep --help)'}; "
          f"{args.repeats} interleaved repeats: median [range]")
    print("workers | pool | Dask, 16-point tasks | Dask, sized tasks | Dask sized / pool | "
          "CPU s: in process, pool, Dask sized (workers + scheduler + client) | in process | load")
    run_sweep(points[:8], evaluate, progress=False)  # numba's kernels compiled / loaded here
    identical = True
    with dask.config.set({k: (v != "False") if v in ("True", "False") else v for k, v in config.items()}), \
            tempfile.TemporaryDirectory(prefix="labkit-bench-sweep-") as folder:
        for n in counts:
            with LoopbackCluster(n, args.timeout, config) as cluster:
                with Client(cluster.address, set_as_default=False) as client:
                    cluster.wait_for_workers(client)
                    client.run(lambda: run_sweep(points[:8], evaluate, progress=False) and None)  # warm
                # the scheduler imports what a task's pickle names (labkit, numpy) at its first graph
                run_sweep(points[:8], evaluate, scheduler=cluster.address, progress=False)
                runs = _measure(n, points, evaluate, cluster, Path(folder), max(1, args.repeats))
                fixed, _ = _timed(lambda: run_sweep(points, evaluate, chunk=16, scheduler=cluster.address,
                                                    progress=False))
            identical &= _same_rows(Path(folder), n)
            print(_row(n, runs, fixed), flush=True)
    print("stored rows: " + ("pool and Dask identical to the in-process map" if identical
                             else "DIFFERENT from the in-process map"))
    return 0 if identical else 1
