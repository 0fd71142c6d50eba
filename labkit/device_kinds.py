"""The words for the device kinds: one per kind, and the old words that still load.

A kind has one word everywhere: the rig file's ``kind = "..."``, a driver's ``kind``, its
package ``labkit/devices/<word>/``, the class of :mod:`labkit.devices.base` and the
accessor of :class:`labkit.protocols.context.RunContext` (``ctx.balance(role)``,
``ctx.tachometer(role)``, ``ctx.motor(role)``, ...). A word used before (``tach``, written in
rig files, recorded sessions and plugin drivers) is read as the kind it names
(docs/decisions/0035-one-name-per-thing.md).
"""

from __future__ import annotations

#: the device kinds, by their one word
DEVICE_KINDS = ("balance", "tachometer", "motor", "camera", "strobe")
#: older words still accepted wherever a kind is read: rig files, drivers, protocols' ``needs``
OLD_KIND_WORDS = {"tach": "tachometer"}


def canonical_kind(word: str) -> str:
    """The kind ``word`` names (an old word gives its kind); any other word is returned as it
    is, for the caller to refuse with its own message."""
    return OLD_KIND_WORDS.get(word, word)
