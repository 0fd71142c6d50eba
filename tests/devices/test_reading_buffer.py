"""labkit.devices.link.ReadingBuffer: the one buffer of a streaming device's readings."""

from __future__ import annotations

import threading

import pytest
from hypothesis import given
from hypothesis import strategies as st

from labkit.devices.link import ReadingBuffer
from labkit.readings import Reading


def reading(t: float) -> Reading:
    return Reading(t, "angular_speed", t * 10.0, "rad/s")


def test_empty_buffer_has_no_latest_and_nothing_since():
    buffer = ReadingBuffer(10)
    assert buffer.latest() is None and buffer.since(float("-inf")) == [] and len(buffer) == 0


@given(times=st.lists(st.floats(0, 1e4), min_size=1, max_size=200).map(sorted),
       t=st.floats(-1.0, 1e4 + 1), history=st.integers(1, 50))
def test_since_is_what_a_plain_filter_of_the_kept_readings_gives(times, t, history):
    buffer = ReadingBuffer(history)
    for x in times:
        buffer.add(reading(x))
    kept = buffer.since(float("-inf"))
    assert history - history // 10 <= len(kept) <= history or len(kept) == len(times)
    assert [r.t for r in kept] == times[len(times) - len(kept):]       # the newest, in order
    assert buffer.since(t) == [r for r in kept if r.t > t]
    assert buffer.latest() == reading(times[-1])


def test_a_reader_thread_and_a_caller_never_see_a_torn_buffer():
    buffer = ReadingBuffer(100)
    done = threading.Event()

    def reader() -> None:
        for i in range(20_000):
            buffer.add(reading(float(i)))
        done.set()

    thread = threading.Thread(target=reader)
    thread.start()
    while not done.is_set():
        seen = buffer.since(-1.0)
        assert [r.t for r in seen] == sorted(r.t for r in seen)
    thread.join()
    assert buffer.latest().t == 19_999.0


def test_history_must_be_positive():
    with pytest.raises(ValueError, match="history 0"):
        ReadingBuffer(0)


def test_what_the_reader_hit_is_raised_to_the_caller_before_any_read():
    def unplugged() -> None:
        raise OSError("device reports readiness to read but returned no data")

    buffer = ReadingBuffer(10, before_read=unplugged)
    buffer.add(reading(1.0))
    for read in (buffer.latest, lambda: buffer.since(0.0)):
        with pytest.raises(OSError, match="returned no data"):
            read()
