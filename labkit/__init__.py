"""labkit: measure, replay and model polarity-free magnetic repulsion (PFR) rigs.

The flat public face for scripts and notebooks (docs/how-to/script-labkit.md, docs/tutorials/notebook.md)::

    import labkit
    rig = labkit.load_rig("rigs/emulated-fig525.toml")
    session = labkit.load_session("sessions/20260101-120000-speed-sweep")
    session.points            # pandas DataFrame, units in the column names
    report = labkit.fit_data([session.path], "power-law")

Every name is imported on first use (PEP 562 ``__getattr__``), so ``import labkit`` and
``labkit --help`` stay fast. The fit function is ``fit_data``, not ``fit``: ``labkit.fit`` is the
subpackage of fit models. The package is typed (``py.typed``).

See README.md for the two commands that set up and run it, and docs/explanation/developing.md for the layout.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from labkit.lazy import lazy_attributes

__version__ = "0.1.0"

#: public name -> the module it lives in, imported on first access
_FACE: dict[str, str] = {
    # rigs and devices
    "load_rig": "labkit.rig",
    "open_rig": "labkit.rig",
    # runs and sessions
    "prepare_run": "labkit.protocols.launch",
    "execute": "labkit.protocols.launch",
    "replay_session": "labkit.protocols.replay",
    "load_session": "labkit.session.dataframes",
    "SessionFrames": "labkit.session.dataframes",
    # video analysis
    "analyse_laser": "labkit.vision.laser.analyse",
    "analyse_strobe": "labkit.vision.strobe.analyse",
    # fits, reports, simulation
    "load_tables": "labkit.fit.data",
    "fit_table": "labkit.fit.table_fit",
    "FitOptions": "labkit.fit.table_fit",
    "build_report": "labkit.report.build",
    "load_scene": "labkit.sim.scene_file",
    "simulate": "labkit.sim.run",
    # errors
    "LabkitError": "labkit.errors",
    "SessionError": "labkit.errors",
}

__all__ = [  # tests/distribution/test_public_face.py checks this equals the names above
    "FitOptions", "LabkitError", "SessionError", "SessionFrames", "__version__", "analyse_laser",
    "analyse_strobe", "build_report", "execute", "fit_data", "fit_table", "load_rig", "load_scene",
    "load_session", "load_tables", "open_rig", "prepare_run", "replay_session", "simulate",
]

if TYPE_CHECKING:  # for type checkers and IDEs; at run time the names come from __getattr__
    from collections.abc import Sequence
    from pathlib import Path

    from labkit.errors import LabkitError, SessionError
    from labkit.fit.data import load_tables
    from labkit.fit.table_fit import FitOptions, FitReport, fit_table
    from labkit.protocols.launch import execute, prepare_run
    from labkit.protocols.replay import replay_session
    from labkit.report.build import build_report
    from labkit.rig import load_rig, open_rig
    from labkit.session.dataframes import SessionFrames, load_session
    from labkit.sim.run import simulate
    from labkit.sim.scene_file import load_scene
    from labkit.vision.laser.analyse import analyse_laser
    from labkit.vision.strobe.analyse import analyse_strobe


def fit_data(inputs: str | Path | Sequence[str | Path], model: str, **options: Any) -> FitReport:
    """Fit sessions, results JSON, CSVs or ``labkit analyse --json`` files against ``model``,
    as ``labkit fit INPUT... --model MODEL`` does; ``options`` are :class:`FitOptions` fields
    (``x``, ``y``, ``sigma``, ``inertia``, ``omega_c``, ``fixed``, ``bootstrap``, ...)."""
    from pathlib import Path

    from labkit.fit.data import load_tables
    from labkit.fit.table_fit import FitOptions, fit_table

    paths = [inputs] if isinstance(inputs, str | Path) else list(inputs)
    return fit_table(load_tables([str(p) for p in paths]), model, FitOptions(**options))


__getattr__ = lazy_attributes(__name__, _FACE)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_FACE))
