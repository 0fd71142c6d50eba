"""The runner's reading log (issue 23): the lines of one read share its time, and a log that runs
while the reader is still adding them must not lose the rest (``protocols.events.not_logged``);
a strobe status line becomes a reading with everything the line said."""

from __future__ import annotations

import bisect
from dataclasses import dataclass

from hypothesis import given
from hypothesis import strategies as st

from labkit.devices.strobe.protocol import parse_status_line
from labkit.protocols.events import not_logged


@dataclass(frozen=True)
class Item:
    t: float
    n: int


def _since(items: list[Item]):
    def since(t: float) -> list[Item]:  # as the drivers' buffers answer: times > t, oldest first
        return items[bisect.bisect_right([i.t for i in items], t):]
    return since


def test_a_line_added_after_the_log_with_the_same_time_is_logged_next_time():
    items = [Item(1.0, 0)]
    logged, mark = not_logged(_since(items), (-1e9, 0))
    items += [Item(1.0, 1), Item(2.0, 2)]        # the rest of the same read, then the next read
    more, mark = not_logged(_since(items), mark)
    assert [i.n for i in logged + more] == [0, 1, 2]
    assert not_logged(_since(items), mark) == ([], mark)


@given(st.lists(st.integers(0, 5), min_size=1, max_size=40), st.lists(st.integers(1, 6), max_size=40))
def test_every_item_is_logged_once_whenever_the_log_runs(times, cuts):
    """Items arrive in time order (several per time); logs run after arbitrary numbers of them."""
    arrived = [Item(float(t), n) for n, t in enumerate(sorted(times))]
    items: list[Item] = []
    logged: list[Item] = []
    mark = (-1e9, 0)
    position = 0
    for cut in [*cuts, len(arrived)]:
        items += arrived[position:position + cut]
        position += cut
        new, mark = not_logged(_since(items), mark)
        logged += new
    assert logged == arrived


def test_a_status_line_becomes_a_reading_with_the_lines_fields():
    status = parse_status_line(b"S,7,3001,66.6667,16.4167,165.0,N", 12.5, "strobe", divider=4)
    row = status.reading().as_json()
    assert row["t"] == 12.5 and row["value"] == 16.4167 and row["unit"] == "Hz"
    assert row["stable"] is False and row["flags"] == ["noisy"]          # a noise pulse: not locked
    assert row["raw"] == "S,7,3001,66.6667,16.4167,165.0,N"
    assert (row["rotor_hz"], row["strobe_hz"], row["divider"], row["seq"]) == (66.6667, 16.4167, 4, 7)
    assert abs(row["apparent_hz"] - (66.6667 - 4 * 16.4167)) < 1e-12
