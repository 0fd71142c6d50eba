"""The line encoding of a cassette's events, schema 2 (docs/decisions/0030-compact-cassettes.md).

A schema-1 line holds every key of its event::

    {"t": 2.2005593789999693, "port": "rotor_motor", "dir": "tx", "data": "hRQb", "enc": "b64",
     "th": "rotor_motor-keepalive", "call": "write"}

(one line in the file).

A schema-2 line leaves out what the reader can restore, and names an event that repeats a recent
one instead of spelling it out again:

* no spaces after ``,`` and ``:``;
* no ``port`` when it is the header's port;
* no ``call`` when it is the operation's own (:data:`DEFAULT_CALLS`: ``write`` for a ``tx``,
  ``read`` for an ``rx`` or a ``short_read``, the event's name for ``reset_input_buffer`` and
  ``close``);
* **a repeat**: an event equal, in everything but its time, to one of the :data:`RECENT`
  distinct events written most recently is written as ``{"t":T,"r":K}``: the K-th most recent
  (1 = the last one). A keep-alive that resends the control loop's last write, a status poll,
  its unchanged reply: ``{"t":2.2005593789999693,"r":1}``.

* **the same time**: no ``t`` when the event has the time of the line before it (a keep-alive
  written in the same tick as the setpoint, an input reset and the query after it, on a virtual
  clock): ``{"r":1}``.

Otherwise the time ``t`` is written in full (Python's shortest repr of the float), so every
event keeps its recorded time bit for bit; only the rest of the line is shortened. Both ends keep the
same list of recent events (:class:`RecentEvents`): a line refers to lines before it, never after,
so a cassette is still written and flushed one whole line per event (a crash loses nothing) and
read front to back in constant memory.
"""

from __future__ import annotations

import json
import math
from typing import Any

#: how many distinct recent events a repeat line may refer to (a motor's status poll cycle is
#: five queries, their replies, the input resets and the two writers' setpoints: about 15)
RECENT = 32

#: the ``call`` an event has when its driver named none: left out of schema-2 lines
DEFAULT_CALLS = {
    "tx": "write",
    "rx": "read",
    "short_read": "read",
    "reset_input_buffer": "reset_input_buffer",
    "close": "close",
}


def _call_key(event: dict[str, Any]) -> str:
    """The key of :data:`DEFAULT_CALLS` for an event: its ``dir``, or a control event's name."""
    return str(event.get("event")) if event.get("dir") == "ctl" else str(event.get("dir"))


def _dumps(obj: dict[str, Any]) -> str:
    return json.dumps(obj, ensure_ascii=False, separators=(",", ":"))


class RecentEvents:
    """The last :data:`RECENT` distinct events (without their time), most recent first. The
    writer and the reader make the same moves, so a repeat line's index means the same to both."""

    def __init__(self) -> None:
        self.keys: list[str] = []
        self.events: list[dict[str, Any]] = []

    def find(self, key: str) -> int | None:
        """The 1-based index of the event with this text, or None."""
        try:
            return self.keys.index(key) + 1
        except ValueError:
            return None

    def use(self, index: int) -> dict[str, Any]:
        """The ``index``-th event (1-based), moved to the front."""
        key, event = self.keys.pop(index - 1), self.events.pop(index - 1)
        self.keys.insert(0, key)
        self.events.insert(0, event)
        return event

    def add(self, key: str, event: dict[str, Any]) -> None:
        self.keys.insert(0, key)
        self.events.insert(0, event)
        if len(self.keys) > RECENT:
            del self.keys[RECENT:], self.events[RECENT:]


class LineEncoder:
    """Turns events into schema-2 lines for one cassette (its header's ``port``)."""

    def __init__(self, port: str) -> None:
        self.port = port
        self.recent = RecentEvents()
        self.last_t: float | None = None

    def encode(self, t: float, body: dict[str, Any]) -> tuple[str, Any]:
        """The line (with its newline) for an event at ``t`` whose other keys are ``body``, and
        a token for :meth:`commit` once the line is safely written."""
        short = dict(body)
        if short.get("port") == self.port:
            del short["port"]
        if "call" in short and short["call"] == DEFAULT_CALLS.get(_call_key(body)):
            del short["call"]
        key = _dumps(short)  # an object with at least "dir": "{...}"
        index = self.recent.find(key)
        when = "" if self._same_time(t) else f'"t":{json.dumps(t)},'
        if index is not None:
            return f'{{{when}"r":{index}}}\n', ("use", index, t)
        return f"{{{when}{key[1:]}\n", ("add", key, short, t)

    def _same_time(self, t: float) -> bool:
        last = self.last_t
        return (last is not None and type(last) is type(t) and last == t
                and math.copysign(1.0, last) == math.copysign(1.0, t))  # -0.0 is written

    def commit(self, token: Any) -> None:
        """Make the move of a written line (a line that never reached the file makes none)."""
        self.last_t = token[-1]
        if token[0] == "use":
            self.recent.use(token[1])
        else:
            self.recent.add(token[1], token[2])


class LineDecoder:
    """Turns schema-2 lines back into full events (as schema 1 held them)."""

    def __init__(self, port: str) -> None:
        self.port = port
        self.recent = RecentEvents()
        self.last_t: Any = None

    def decode(self, obj: dict[str, Any]) -> dict[str, Any]:
        """The full event of a parsed line; ValueError for a repeat of nothing."""
        if "r" in obj:
            index, known = obj["r"], len(self.recent.keys)
            if not isinstance(index, int) or isinstance(index, bool) or not 1 <= index <= known:
                raise ValueError(f"key 'r': {index!r} is not one of the {known} recent events")
            short = self.recent.use(index)
        else:
            short = {k: v for k, v in obj.items() if k != "t"}
            self.recent.add(_dumps(short), short)
        t = obj["t"] if "t" in obj else self.last_t
        self.last_t = t
        event: dict[str, Any] = {"t": t, "port": self.port, **short}
        if "call" not in event and _call_key(event) in DEFAULT_CALLS:
            event["call"] = DEFAULT_CALLS[_call_key(event)]
        return event
