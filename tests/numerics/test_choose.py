"""Order chosen by target: 6th and 8th order compositions and ``--target-error``."""

from __future__ import annotations

import math

import pytest

from labkit.cli import main
from labkit.numerics import metrics
from labkit.numerics.checks import NumericsError
from labkit.numerics.choose import choose
from labkit.sim import compile_scene, load_scene, simulate

KW = {"samples_per_period": 1, "drift_threshold": math.inf, "rotation_threshold": math.inf}


def _error(scene, system, run, ref):
    moments = [b.moment_Am2 for b in scene.bodies]
    return metrics.state_errors(run, ref, system.length_scale, system.omega, moments).final


@pytest.mark.parametrize(("name", "order"), [("kahanli6", 6), ("yoshida8", 8), ("kahanli8", 8)])
def test_new_compositions_have_their_order(name, order):
    scene = load_scene("mbs_fig6_1")
    system = compile_scene(scene)
    ref = simulate(scene, 5, "yoshida6", steps_per_period=1024, system=system, **KW)
    steps = [16, 32]
    errors = [_error(scene, system, simulate(scene, 5, name, steps_per_period=n, system=system, **KW), ref)
              for n in steps]
    assert abs(math.log2(errors[0] / errors[1]) - order) < 0.4, errors


@pytest.mark.parametrize("scene_name", ["conical_5_1", "mbs_fig6_1"])
@pytest.mark.parametrize("target", [1e-5, 1e-9])
def test_target_error_is_reached_with_a_bounded_invariant(scene_name, target):
    scene = load_scene(scene_name)
    system = compile_scene(scene)
    cycles = 50
    ref = simulate(scene, cycles, "kahanli8", steps_per_period=128, system=system, **KW)
    choice = choose(scene, system, cycles, target)
    run = simulate(scene, cycles, choice.integrator, steps_per_period=choice.steps_per_period, system=system,
                   **KW)
    assert _error(scene, system, run, ref) <= target
    assert run.invariant_drift < 1e-8
    if target <= 1e-9:
        assert choice.integrator in ("kahanli6", "kahanli8")


def test_simulate_target_error_prints_its_choice(capsys):
    assert main(["simulate", "conical_5_1", "--cycles", "20", "--target-error", "1e-8"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("chose kahanli") and "estimated error" in out and "status     ok" in out


def test_unreachable_targets_fail_with_one_line(capsys):
    assert main(["simulate", "conical_5_1", "--cycles", "1e5", "--target-error", "1e-14"]) == 2
    assert "below the round-off" in capsys.readouterr().err
    assert main(["simulate", "pendulum_5_484", "--target-error", "1e-6"]) == 2
    assert "rigid-body splittings" in capsys.readouterr().err
    with pytest.raises(NumericsError):
        choose(load_scene("conical_5_1"), compile_scene(load_scene("conical_5_1")), 10, 1e-20)
