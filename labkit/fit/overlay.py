"""Model overlays: a simulator's (or closed form's) prediction drawn over fitted data.

The hook is deliberately plain data: an :class:`Overlay` is a label and x/y arrays in the
data's units, optionally tied to one series. Build one from any function of x with
:func:`overlay_from_function`, e.g. the simulated cone angle for the rig's magnets at each
measured speed::

    ov = overlay_from_function("simulated (labkit.sim)", simulate_cone_angle, speeds)
    fit_figure(report, "fit.png", overlays=[ov])
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Overlay:
    label: str
    x: np.ndarray
    y: np.ndarray
    series: str | None = None   # None: drawn on every series' panel
    x_name: str | None = None   # column names of x and y; None: drawn on any figure
    y_name: str | None = None

    def fits(self, x_name: str, y_name: str) -> bool:
        """True when this overlay is in the units of a figure of ``x_name`` against ``y_name``."""
        return self.x_name in (None, x_name) and self.y_name in (None, y_name)


def overlay_from_function(label: str, fn: Callable[[float], float], x, series: str | None = None,
                          x_name: str | None = None, y_name: str | None = None) -> Overlay:
    """Evaluate ``fn`` at each x (a scalar function, e.g. one simulation per speed)."""
    xs = np.asarray(x, dtype=float)
    ys = np.array([float(fn(float(v))) for v in xs])
    return Overlay(label, xs, ys, series, x_name, y_name)


def overlays_from_csv(path) -> list[Overlay]:
    """Overlays from a CSV (e.g. a simulator's output): the first column is x, every other
    numeric column one curve, drawn on figures with the same x and y column names."""
    from pathlib import Path

    from labkit.errors import DataFileError
    from labkit.fit.data import load_table

    table = load_table(path)
    names = list(table.numeric)
    if len(names) < 2:
        raise DataFileError(str(path), "", "an overlay CSV needs an x column and at least one y column")
    x_name = names[0]
    order = np.argsort(table.numeric[x_name], kind="stable")
    stem = Path(path).stem
    return [Overlay(f"{stem}: {y}", table.numeric[x_name][order], table.numeric[y][order],
                    x_name=x_name, y_name=y) for y in names[1:]]
