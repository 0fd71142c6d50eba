"""What every integrator returns (:class:`RawRun`), the error it raises, and the bound on a run's
samples in memory (:func:`check_memory`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from labkit.errors import LabkitError

if TYPE_CHECKING:  # annotations only: `labkit simulate --help` reads the names below without numpy
    import numpy as np

MAX_SAMPLE_BYTES = 1 << 30


class SimulationError(LabkitError):
    """A simulation cannot run as asked (unknown integrator, horizon too long for memory, ...)."""


@dataclass
class RawRun:
    """What an integrator returns: samples of the (principal-frame) state and how it ended."""

    integrator: str
    setting: dict
    status: int  # 0 ok, 1 nan, 2 blowup, 3 contact, 4 escape, 5 solver failed
    event_time: float
    n_force: int
    t: np.ndarray
    x: np.ndarray | None = None  # (n, nb, 3)
    v: np.ndarray | None = None
    R: np.ndarray | None = None  # (n, nb, 3, 3), principal frame -> lab
    L: np.ndarray | None = None  # (n, nb, 3), lab angular momentum
    y: np.ndarray | None = None  # reduced angle (n,)
    yd: np.ndarray | None = None  # reduced rate (n,)
    impulse: np.ndarray | None = None  # (nb, 3) time integral of magnetic force
    budget: np.ndarray | None = None  # (n,) damping's accumulated change of E - wz J_z
    message: str = ""
    extra: dict = field(default_factory=dict)


def check_memory(n_samples: int, nb: int) -> None:
    size = n_samples * max(nb, 1) * 18 * 8
    if size > MAX_SAMPLE_BYTES:
        raise SimulationError(
            f"{n_samples} samples of {nb} bodies need {size / 2**30:.1f} GiB: "
            "lower --cycles or the samples per period"
        )
