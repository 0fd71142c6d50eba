"""Quick fits written into results.json (the full fitting machinery is :mod:`labkit.fit`).

They are deliberately not :mod:`labkit.fit`'s fits: the power law here is least squares in
y (``labkit.fit`` fits ln y) and the Eq. 6.37 fit minimises residuals in ``w^2 - v w``
(``labkit.fit`` in v_S), so the numbers differ in the 3rd-4th digit, and recorded sessions
replay bit-for-bit against the results.json these functions wrote.

* :func:`quick_fit_power_law`: model ``power-law`` (the spelling of :mod:`labkit.fit`'s model
  registry), ``y = a x^b`` as the paper plots Fig. 5.25 (x in RPM, y in grams
  force; the paper found a = 224e6, b = -1.9).
* :func:`fit_spin_critical_c`: Eq. 6.37, ``-k w^2 = C (1 - w/w_ref)`` with ``k = v/w - 1``;
  linear in C, so it is a one-parameter least-squares fit through the origin of
  ``y = w^2 - v w`` against ``x = 1 - w/w_ref`` (paper: C = 4.7e5 and 6.63e5, w_ref = 3000).
"""

from __future__ import annotations

import math

#: what each quick fit minimises, and what ``labkit fit`` minimises instead (docs/reference/fitting.md)
RESIDUALS = {
    "power-law": ("least squares in y (grams)", "labkit fit --model power-law fits ln y"),
    "eq6.37": ("least squares in w^2 - v w", "labkit fit --model spin-critical fits the spin v"),
}


def quick_fit_label(model: str) -> str:
    """The words ``labkit run`` prints beside a quick fit, so it is not mistaken for
    ``labkit fit``'s (same model, other residuals: the digits differ, docs/reference/fitting.md)."""
    mine, theirs = RESIDUALS.get(model, ("least squares", "labkit fit may differ"))
    return f"{model}, {mine}; {theirs}, see docs/reference/fitting.md"


def _param(value: float, stderr: float) -> dict[str, float]:
    return {"value": float(value), "stderr": float(stderr)}


def quick_fit_power_law(x: list[float], y: list[float], sigma: list[float] | None = None) -> dict:
    """Weighted least squares of ``y = a x^b`` in y, started from a log-log line (Needs y > 0):
    :func:`labkit.fit.models.power_law.least_squares_power_law`, the live view's fit too."""
    from labkit.fit.models.power_law import least_squares_power_law  # the CLI starts fast without a fit

    fit = least_squares_power_law(x, y, sigma, residuals="linear")
    return {"model": "power-law", "formula": "y = a * x^b", "x": "speed_rpm", "y": "force_g",
            "params": {"a": _param(fit.a, fit.stderr_a), "b": _param(fit.b, fit.stderr_b)},
            "n": fit.n}


def fit_spin_critical_c(rotor_rad_s: list[float], spin_rad_s: list[float], w_ref: float = 3000.0) -> dict:
    """C of Eq. 6.37 from (rotor speed w, floator spin v) pairs at the drop, with its stderr."""
    import numpy as np
    w, v = np.asarray(rotor_rad_s, float), np.asarray(spin_rad_s, float)
    if len(w) < 1:
        raise ValueError("Eq. 6.37 fit needs at least one (rotor, spin) pair")
    x = 1.0 - w / w_ref
    y = w**2 - v * w          # = -k w^2 with k = v/w - 1
    c = float(np.sum(x * y) / np.sum(x * x))
    dof = len(w) - 1
    stderr = float(math.sqrt(np.sum((y - c * x) ** 2) / dof / np.sum(x * x))) if dof > 0 else math.nan
    return {"model": "eq6.37", "formula": "-k w^2 = C (1 - w/w_ref), k = v/w - 1",
            "x": "rotor_rad_s", "y": "spin_rad_s",
            "params": {"C": _param(c, stderr)}, "fixed": {"w_ref_rad_s": float(w_ref)}, "n": int(len(w))}
