"""Fig. 6.18 from the model: the critical spin of the shipped emulated-fig618 rig against the
paper's series 1 and against Eq. 6.37 with the C derived from the rig (docs/explanation/twin.md).

    python analysis/fig618_model_curve.py [RIG]

At each of the paper's rotor speeds the spin k of Eq. 5.62 is found at which the held floator's
weakest hold (min over the height of PFR + weight - attraction, the floator's co-rotating steady
state with that spin) reaches zero: the model's own break-up with spin. Prints the model's v,
the plant law's v (Eq. 6.37, C from labkit.emulators.break_up) and the paper's v, and the C of
Eq. 6.37 fitted to the model's curve. About 20 s.
"""

from __future__ import annotations

import sys

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from labkit.emulators.break_up import W_REF_RAD_S, break_up
from labkit.emulators.rig_plant import SpinCriticalLaw
from labkit.emulators.twin_model import params_from_rig
from labkit.model.floator_equilibrium import FloatorSetup, steady_state
from labkit.reproduce.paper_data import FIG_6_18
from labkit.rig import bundled_rig_path, load_rig
from labkit.units import G0


def main() -> None:
    rig = sys.argv[1] if len(sys.argv) > 1 else bundled_rig_path("emulated-fig618")
    p = params_from_rig(load_rig(rig))
    b = break_up(p)
    law = SpinCriticalLaw(c=b.c)
    print(f"break-up: omega_0 = {b.omega_rad_s:.2f} rad/s, r_0 = {b.gap_m * 1e3:.2f} mm, "
          f"phi_0 = {b.phi:.4f} rad, C = {b.c:.4g}")

    def weakest(w: float, k: float) -> float:
        def net(r: float) -> float:
            setup = FloatorSetup(p.m_rotator, p.m_floator, p.mass_kg, p.i_radial, p.i_axial, w, p.tilt_rad, k)
            st = steady_state(setup, r)
            return st.force_cyclic_z + st.force_static_z + p.mass_kg * G0
        return minimize_scalar(net, bounds=(0.8 * b.gap_m, 1.2 * b.gap_m), method="bounded",
                               options={"xatol": 1e-9}).fun

    ws, vs = [], []
    print(" omega   model_v   law_v  paper_v  (model-law)/w  (model-paper)/w")
    for w, v_paper in zip(FIG_6_18["s1"]["omega"], FIG_6_18["s1"]["v"], strict=True):
        if w <= b.omega_rad_s:
            print(f"{w:6.0f}   below the model's break-up speed")
            continue
        k = brentq(lambda kk, w=w: weakest(w, kk), -1.0, -0.1, xtol=1e-9)
        v = (k + 1.0) * w
        ws.append(w)
        vs.append(v)
        v_law = law.critical_spin(w)
        print(f"{w:6.0f} {v:9.1f} {v_law:7.1f} {v_paper:8.0f} {(v - v_law) / w:+13.4f} "
              f"{(v - v_paper) / w:+16.4f}")
    w_arr, v_arr = np.asarray(ws), np.asarray(vs)
    lhs = -(v_arr / w_arr - 1.0) * w_arr**2
    shape = 1.0 - w_arr / W_REF_RAD_S
    print(f"C of Eq. 6.37 fitted to the model's curve: {np.sum(lhs * shape) / np.sum(shape**2):.4g}")


if __name__ == "__main__":
    main()
