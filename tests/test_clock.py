"""The Clock is the one source of time: virtual time jumps and runs due jobs in order."""

from labkit.io.clock import RealClock, VirtualClock, current_clock, use_clock


def test_virtual_sleep_jumps_and_runs_periodic_jobs_in_time_order():
    clock = VirtualClock()
    seen: list[tuple[str, float]] = []
    clock.every(0.1, lambda t: seen.append(("fast", round(t, 9))))
    clock.every(0.25, lambda t: seen.append(("slow", round(t, 9))))
    clock.sleep(0.5)
    assert clock.now() == 0.5
    times = [t for _, t in seen]
    assert times == sorted(times)
    assert [n for n, _ in seen].count("fast") == 5
    assert [n for n, _ in seen].count("slow") == 2


def test_cancelled_job_stops_running():
    clock = VirtualClock()
    calls: list[float] = []
    job = clock.every(0.1, calls.append)
    clock.sleep(0.35)
    job.cancel()
    clock.sleep(1.0)
    assert len(calls) == 3


def test_real_clock_job_runs_on_its_own_thread():
    clock = RealClock()
    calls: list[float] = []
    job = clock.every(0.01, calls.append)
    clock.sleep(0.1)
    job.cancel()
    assert len(calls) >= 2


def test_use_clock_installs_and_restores():
    before = current_clock()
    with use_clock(VirtualClock(5.0)) as clock:
        assert current_clock() is clock and clock.now() == 5.0
    assert current_clock() is before
