"""A simulated run logged to rerun holds each body's pose over sim_time, its trace and the drift."""

import numpy as np

from labkit.sim.run import simulate
from labkit.stream.readback import column, entity_paths
from labkit.stream.sim import stream_sim_result


def test_conical_scene_streams_pose_trace_tilt_and_invariant(tmp_path):
    result = simulate("conical_5_1", cycles=3)
    rrd = tmp_path / "sim.rrd"
    stream_sim_result(f"save:{rrd}", result)
    name = result.body_names[0]
    assert {f"/world/{name}", f"/world/{name}/trace", f"/world/{name}/dipole",
            f"/sim/{name}/tilt_rad", "/sim/invariant", "/log"} <= entity_paths(rrd)
    times, tilts = column(rrd, f"/sim/{name}/tilt_rad", "Scalars:scalars", "sim_time")
    assert len(tilts) == len(result.times_s)
    # the logged tilt is the angle of the body's axis (its dipole, body z) to lab z, computed here
    expected = np.arccos(np.clip(result.axes[:, 0, 2], -1, 1))
    assert np.allclose([v[0] for v in tilts], expected, atol=1e-9)


def test_simulate_cli_with_rerun_writes_the_rrd(tmp_path, capsys):
    from labkit.cli import main

    rrd = tmp_path / "cli.rrd"
    main(["simulate", "conical_5_1", "--cycles", "2", "--rerun", f"save:{rrd}"])
    assert "/sim/invariant" in entity_paths(rrd)
