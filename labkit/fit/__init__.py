"""Fitting measurements against the PFR model, with uncertainties (see docs/reference/fitting.md).

Public entry points:

* :func:`labkit.fit.load_table` (or :func:`labkit.fit.load_tables` for several files, folders
  or globs, e.g. one analysis JSON per video clip) + :func:`labkit.fit.fit_table` -- what
  ``labkit fit`` runs; :func:`labkit.fit.write_table` writes the collected rows as CSV;
* the per-model functions in :mod:`labkit.fit.models` (``fit_power_law``, ``fit_pfr_force``,
  ``fit_spin_critical``, ``fit_cone_angle``, ``fit_mbs_force``, ``fit_mbs_parts``,
  ``fit_mbs_distance``), each returning a :class:`FitResult`;
* :class:`labkit.fit.overlay.Overlay` to draw a simulator's prediction on a fit figure.
"""

from labkit.errors import FitError
from labkit.fit.data import Table, load_table, load_tables, to_si, write_table
from labkit.fit.models import MODELS
from labkit.fit.result import FitResult, ParamEstimate
from labkit.fit.table_fit import FitOptions, FitReport, fit_table

__all__ = ["MODELS", "FitError", "FitOptions", "FitReport", "FitResult", "ParamEstimate", "Table",
           "fit_table", "load_table", "load_tables", "to_si", "write_table"]
