"""Which plant an emulated rig gets, by name, and the plants of one emulated rig, scoped.

Presets (the part of ``plant=`` before the first dot in a ``sim://`` URL): ``fig525`` and
``fig618`` (and any other name) are the fitted laws of :mod:`labkit.emulators.rig_plant`;
``model-fig525`` and ``model-fig618`` the model plant of :mod:`labkit.emulators.model_plant`
(docs/explanation/twin.md), which the shipped emulated rigs use. Every sim:// port of the current
:class:`Emulation` shares its plants by name (docs/decisions/0006-scoped-emulations.md).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from labkit.emulators.rig_plant import RigPlant, fig618_plant

#: plant presets by name; ``plant=fig618`` or ``plant=fig618.anything`` in a sim:// URL
PLANT_PRESETS: dict[str, Callable[[int], RigPlant]] = {
    "fig525": lambda seed: RigPlant(seed=seed),
    "fig618": fig618_plant,
}


def make_plant(name: str, seed: int = 0, rig: Any = None) -> RigPlant:
    """A fresh plant for ``name``: the preset named by the part before the first dot, else the
    fitted law of Fig. 5.25. ``model-fig525`` / ``model-fig618`` build the model plant of
    :mod:`labkit.emulators.model_plant` from ``rig`` (a loaded rig file; None: the magnets of
    the shipped emulated rig of that preset)."""
    head = name.split(".", 1)[0]
    if head.startswith("model-"):
        from labkit.emulators.model_plant import MODEL_PRESETS, model_plant
        from labkit.emulators.twin_model import params_from_rig
        if head not in MODEL_PRESETS:
            raise ValueError(f"plant={name}: unknown model preset {head!r} (use {', '.join(MODEL_PRESETS)})")
        return model_plant(head, seed, params_from_rig(rig) if rig is not None else None)
    preset = PLANT_PRESETS.get(head)
    return preset(seed) if preset else RigPlant(seed=seed)


class Emulation:
    """The plants of one emulated rig: ``sim://`` ports opened while it is current share its
    plants by name (``plant=fig525`` in their URLs), so a balance sees the speed its motor
    emulator reached. Scope one with ``with use_emulation(Emulation()) as emu:``; each test
    of labkit's suite gets its own (tests/conftest.py). Decision record:
    docs/decisions/0006-scoped-emulations.md."""

    def __init__(self, name: str = "", rig: Any = None, seed: int = 0) -> None:
        self.name = name
        #: the rig file whose magnets and geometry model plants are built from (None: defaults)
        self.rig = rig
        self.seed = seed
        self._plants: dict[str, RigPlant] = {}
        self._lock = threading.Lock()

    def plant(self, name: str, seed: int = 0) -> RigPlant:
        """The plant called ``name`` (created on first use; names starting with a preset such
        as ``fig525``, ``fig618``, ``fig618.test3`` get that preset)."""
        with self._lock:
            if name not in self._plants:
                self._plants[name] = make_plant(name, seed or self.seed, self.rig)
            return self._plants[name]

    def plants(self) -> dict[str, RigPlant]:
        with self._lock:
            return dict(self._plants)

    def clear(self) -> None:
        """Forget every plant (the next run starts from rest)."""
        with self._lock:
            self._plants.clear()

    def bind_rig(self, rig: Any) -> None:
        """Build model plants from ``rig`` from now on (forgets the plants built so far)."""
        with self._lock:
            self.rig = rig
            self._plants.clear()

    def __repr__(self) -> str:
        return f"Emulation({self.name!r}, plants={sorted(self._plants)})"


#: the emulation of a process that scopes none (``labkit run``, ``labkit emulate``)
_PROCESS_EMULATION = Emulation("process")
_stack: list[Emulation] = []
_stack_lock = threading.Lock()


def current_emulation() -> Emulation:
    """The innermost emulation made current by :func:`use_emulation` (any thread sees it:
    emulators are built when their port opens, sometimes on a driver's reader thread), else
    the process's own."""
    with _stack_lock:
        return _stack[-1] if _stack else _PROCESS_EMULATION


@contextmanager
def use_emulation(emulation: Emulation | None = None) -> Iterator[Emulation]:
    """Make ``emulation`` (default: a new one) current inside the ``with`` block."""
    emu = emulation if emulation is not None else Emulation()
    with _stack_lock:
        _stack.append(emu)
    try:
        yield emu
    finally:
        with _stack_lock:
            _stack.remove(emu)


def shared_plant(name: str, seed: int = 0) -> RigPlant:
    """The current emulation's plant called ``name`` (:meth:`Emulation.plant`)."""
    return current_emulation().plant(name, seed)


def reset_plants() -> None:
    """Forget the current emulation's plants (:meth:`Emulation.clear`)."""
    current_emulation().clear()
