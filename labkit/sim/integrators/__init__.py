"""Integrators for compiled scenes.

* ``auto`` (default): the composition and step chosen per scene by
  :func:`labkit.sim.integrators.splitting_run.auto_composition`
  (``splitting4`` for a driven body, ``kahanli8`` for interacting free bodies);
* ``splitting4`` (Suzuki 5-stage order 4), ``yoshida4``, ``yoshida6``, ``kahanli6``, ``kahanli8``,
  ``strang``: fixed step ``h = T/N`` kick-rotate-kick splittings with exact free rotation
  (numba, cached);
* ``dop853``, ``radau``, ``lsoda``: :func:`scipy.integrate.solve_ivp` references with
  per-component (scaled) tolerances;
* ``cyrk-dop853``: the same DOP853 compiled (CyRK's C++ solver with a numba right-hand side),
  the fair peer of ``labkit bench sim``.

Every integrator returns a :class:`labkit.sim.integrators.raw_run.RawRun`; :func:`labkit.sim.run.simulate`
turns it into a :class:`labkit.sim.result.SimResult` with invariants, status and quantities of interest.
"""

from __future__ import annotations

from labkit.sim.integrators.raw_run import SimulationError

SPLITTINGS = {
    "auto": "auto",
    "splitting4": "suzuki4",
    "suzuki4": "suzuki4",
    "yoshida4": "yoshida4",
    "yoshida6": "yoshida6",
    "kahanli6": "kahanli6",
    "yoshida8": "yoshida8",
    "kahanli8": "kahanli8",
    "strang": "strang",
}
REFERENCES = {"dop853": "DOP853", "radau": "Radau", "lsoda": "LSODA"}
#: compiled peers (CyRK's C++ solver, numba right-hand side; the optional ``bench`` extra)
COMPILED = {"cyrk-dop853": "DOP853"}
INTEGRATORS = sorted(set(SPLITTINGS) | set(REFERENCES) | set(COMPILED))
DEFAULT_INTEGRATOR = "auto"


def get_integrator(name: str):
    """Look up an integrator's run function by name."""
    key = name.lower()  # each family imported when asked for (scipy only for its references)
    if key in SPLITTINGS:
        from labkit.sim.integrators import splitting_run

        return lambda system, cycles, **kw: splitting_run.run(system, cycles, SPLITTINGS[key], name=key, **kw)
    if key in REFERENCES:
        from labkit.sim.integrators import reference

        return lambda system, cycles, **kw: reference.run(system, cycles, REFERENCES[key], name=key, **kw)
    if key in COMPILED:
        from labkit.sim.integrators import compiled_reference

        method = COMPILED[key]
        return lambda system, cycles, **kw: compiled_reference.run(system, cycles, method, name=key, **kw)
    raise SimulationError(f"unknown integrator {name!r} (choose from {', '.join(INTEGRATORS)})")
