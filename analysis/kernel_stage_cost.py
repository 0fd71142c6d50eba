"""Cost of one stage (one force evaluation) of the splitting kernels, per bundled scene:
the general kernel against the kernel specialised to the scene's shape (docs/reference/simulator.md).

    python analysis/kernel_stage_cost.py [--cycles 1000] [--repeats 5]

Then 1e4 cycles of the one-body and the two-body scene with the default integrator (issue 15:
<= 0.25 s and <= 1 s of kernel time), in CPU seconds including result assembly.

CPU time (time.process_time, so other jobs on a shared machine disturb it less than wall time),
the minimum of ``--repeats`` interleaved runs, suzuki4 at N = 64, one sample per period.
"""

from __future__ import annotations

import argparse
import time

from labkit.sim import compile_scene, load_scene, simulate
from labkit.sim.integrators import splitting_run
from labkit.sim.integrators.shapes import scene_shape
from labkit.sim.integrators.splitting import COMPOSITIONS

SCENES = ("conical_5_1", "fig5_13", "mbs_fig6_1", "fig5_7")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cycles", type=int, default=1000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    weights = COMPOSITIONS["suzuki4"][0]
    print(f"ns per stage (CPU, min of {args.repeats}), suzuki4 N=64, {args.cycles} cycles:")
    for name in SCENES:
        system = compile_scene(load_scene(name))
        h, n = system.period / 64, args.cycles * 64
        kernels = ["general"] + ([scene_shape(system)] if scene_shape(system) != "general" else [])
        best = dict.fromkeys(kernels, float("inf"))
        for kernel in kernels:  # load or compile
            splitting_run._integrate_rigid(system, weights, kernel, 0.0, h, 64, 64, 3)
        for _ in range(args.repeats):
            for kernel in kernels:
                start = time.process_time()
                splitting_run._integrate_rigid(system, weights, kernel, 0.0, h, n, 64, n // 64 + 2)
                best[kernel] = min(best[kernel], time.process_time() - start)
        stages = n * len(weights)
        cells = "  ".join(f"{k} {v * 1e9 / stages:5.1f}" for k, v in best.items())
        print(f"  {name:12s} {cells}")
    print("1e4 cycles, default integrator (auto), CPU seconds of the run (min of 3):")
    for name in ("conical_5_1", "mbs_fig6_1"):
        scene = load_scene(name)
        system = compile_scene(scene)
        simulate(scene, 1, system=system)
        best = float("inf")
        for _ in range(3):
            start = time.process_time()
            res = simulate(scene, 10_000, system=system, samples_per_period=1)
            best = min(best, time.process_time() - start)
        setting = res.setting
        print(f"  {name:12s} {best:.3f} s  ({setting['composition']} N={setting['steps_per_period']}, "
              f"kernel {setting['kernel']}, "
              f"drift {res.invariant_drift:.2g})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
