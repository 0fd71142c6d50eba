"""How a run ended: named status codes and their messages (in the style of scipy's ``OdeSolver``
``status`` and ``MESSAGES``). Kernels return the integer value; :func:`labkit.sim.run.simulate`
turns it into ``SimResult.status`` (the ``name``) and ``status_detail`` (the message)."""

from __future__ import annotations

from enum import IntEnum


class Status(IntEnum):
    OK = 0
    NONFINITE = 1
    BLOWUP = 2
    CONTACT = 3
    ESCAPE = 4
    SOLVER_FAILED = 5

    @property
    def label(self) -> str:
        """The ``SimResult.status`` string."""
        return LABELS[self]


#: ``SimResult.status`` of each code (stable strings: JSON results and tests use them)
LABELS = {
    Status.OK: "ok",
    Status.NONFINITE: "nan",
    Status.BLOWUP: "blowup",
    Status.CONTACT: "contact",
    Status.ESCAPE: "escape",
    Status.SOLVER_FAILED: "solver_failed",
}

#: what each code means, for ``SimResult.status_detail``
MESSAGES = {
    Status.OK: "",
    Status.NONFINITE: "non-finite state",
    Status.BLOWUP: "state ran away (|omega| > 1e9 rad/s or |v| > 1e6 m/s)",
    Status.CONTACT: "bodies touched",
    Status.ESCAPE: "a body went beyond {r_escape:.4g} m from the others",
    Status.SOLVER_FAILED: "solver failed: {message}",
}
