"""What the built-in protocols declare about their data: the row each step produces, and
the paper's figure it is drawn as (Fig. 5.25 for ``speed-sweep``, Fig. 6.18 for
``spin-critical``, Eq. 5.24 for ``cone-sweep``, Eq. 5.97 for ``strobe-sweep``), with the fits the
live view and the report make (ADR 0021).

The types are :mod:`labkit.hints`'; the protocols point at these declarations
(``SpeedSweep.hints = FIG_5_25``), and :mod:`labkit.protocols.legacy_hints` gives them to
sessions recorded before the start document carried hints.
"""

from __future__ import annotations

from labkit.hints import Column, Curve, Hints, ReportFit, Series

#: the paper's Fig. 5.25: y [g] = 224e6 x [RPM]^-1.9
PAPER_FIG525 = Curve("paper", "y = 224e6 x^-1.9", "power-law", {"a": 224e6, "b": -1.9}, figure="Fig. 5.25")
#: the paper's Fig. 6.18, series 1: Eq. 6.37 with C = 4.7e5 s^-2 and omega_c = 3000 rad/s
PAPER_FIG618 = Curve("paper", "Eq. 6.37, C = 4.7e5 s^-2, omega_c = 3000 rad/s", "spin-critical",
                     {"C": 4.7e5, "omega_c": 3000.0}, figure="Fig. 6.18")

_NO_INERTIA = " (no floator inertia in the rig file: K/I and tau_S/I are reported)"

FIG_5_25 = Hints(
    x="speed_rpm", y="force_g", x_name="rotor speed", x_unit="RPM", y_name="force", y_unit="g",
    figure="Fig. 5.25", root="/fig5_25", fit="power-law", residual="ratio", reference=PAPER_FIG525,
    report_title="PFR force vs rotor speed (cf. paper Fig. 5.25)",
    report_fits=(
        ReportFit("power-law", "Power law y = a x^b (Fig. 5.25)", "power-law",
                  "PFR force vs rotor speed (cf. paper Fig. 5.25)", reference=True),
        ReportFit("pfr-omega2", "Eq. 5.81 with tau_S = 0: F = K / (I omega^2)", "pfr-force",
                  fixed={"tau_S": 0.0}, inertia=True),
        ReportFit("pfr-force", "Eq. 5.81: F = K / (I omega^2 - tau_S)", "pfr-force", inertia=True),
    ))

FIG_6_18 = Hints(
    x="rotor_rad_s", y="spin_rad_s", x_name="rotor speed", x_unit="rad/s", y_name="spin", y_unit="rad/s",
    figure="Fig. 6.18", title="spin [rad/s] against rotor speed [rad/s] at the drop", root="/fig6_18",
    fit="spin-critical", residual="difference", legend_corner="LeftTop",
    reference=PAPER_FIG618,
    report_title="Spin-critical pairs (cf. paper Fig. 6.18)",
    report_fits=(
        ReportFit("eq637", "Eq. 6.37 with omega_c = 3000 rad/s (paper)", "spin-critical",
                  "Spin-critical pairs (cf. paper Fig. 6.18)", omega_c=3000.0, reference=True),
        ReportFit("eq637-fit", "Eq. 6.37 with omega_c fitted", "spin-critical", omega_c="fit"),
        ReportFit("eq569", "Eq. 5.69 (no omega_c term)", "spin-critical", omega_c="inf"),
    ),
    notes=("The paper's caption fits give C = 4.7e5 (series 1) and 6.63e5 (series 2) with "
           "omega_c = 3000 rad/s.",))

SPEED_SWEEP_ROW = (
    Column("step", "", "index of the step in the plan"),
    Column("direction", "", "up or down (a hysteresis sweep's second leg)"),
    Column("repeat", "", "repeat number, from 0"),
    Column("target_rpm", "RPM", "the step's target speed"),
    Column("speed_rad_s", "rad/s", "mean measured rotor speed while recording"),
    Column("speed_rpm", "RPM", "the same in RPM"),
    Column("speed_std_rpm", "RPM", "standard deviation of the measured speed"),
    Column("force_n", "N", "mean force at speed minus the drift-corrected rest reading"),
    Column("force_g", "g", "the same in grams-force"),
    Column("force_stderr_n", "N", "standard error of the mean force"),
    Column("force_stderr_g", "g", "the same in grams-force"),
    Column("n", "", "number of balance readings averaged"),
    Column("settle_time_s", "s", "time the speed loop took to settle"),
    Column("drift_n", "N", "rest reading interpolated to the middle of the recording"),
    Column("drift_g", "g", "how far the zero moved between the rest readings before and after the "
                           "step (null when zero=start did not measure it)"),
    Column("unstable", "", "readings the balance flagged as not stable"),
    Column("warnings", "", "what makes the point doubtful (the zero's drift against drift_warn)"),
)

SPIN_CRITICAL_ROW = (
    Column("step", "", "index of the step in the plan"),
    Column("target_rpm", "RPM", "the step's rotor target"),
    Column("rotor_rad_s", "rad/s", "rotor speed at the drop (mean of the trials used)"),
    Column("rotor_rpm", "RPM", "the same in RPM"),
    Column("spin_rad_s", "rad/s", "floator spin just before the drop (median of the trials used)"),
    Column("spin_rpm", "RPM", "the same in RPM"),
    Column("rotor_std_rad_s", "rad/s", "spread (standard deviation) of the rotor speeds of the trials used; "
                                       "null with one trial (the report's error bars)"),
    Column("spin_std_rad_s", "rad/s", "spread of the spins of the trials used; null with one trial"),
    Column("k", "", "v/w - 1 (Eq. 6.37)"),
    Column("consistent", "", "the last consistent_n spins agreed within consistency_pct"),
    Column("trials", "", "each trial: rotor_rad_s, spin_rad_s, cause, hold_s"),
    Column("no_drop", "", "no trial dropped the floator"),
)


EQ_5_24 = Hints(
    x="speed_rpm", y="cone_angle_deg", x_name="rotor speed", x_unit="RPM", y_name="cone angle",
    y_unit="deg", figure="Eq. 5.24", title="cone angle [deg] against rotor speed [RPM]", root="/eq5_24",
    fit="cone-angle", residual="difference",
    report_title="Cone angle vs rotor speed (Eq. 5.24)",
    report_fits=(
        ReportFit("cone-angle", "Eq. 5.24 / 5.68: tau_C and tau_S", "cone-angle",
                  "Cone angle vs rotor speed (Eq. 5.24)", inertia=True, y="cone_angle_rad"),
        ReportFit("cone-angle-s0", "Eq. 5.24 with tau_S = 0", "cone-angle", fixed={"tau_S": 0.0},
                  inertia=True, y="cone_angle_rad"),
    ))

CONE_SWEEP_ROW = (
    Column("step", "", "index of the step in the plan"),
    Column("target_rpm", "RPM", "the step's target speed"),
    Column("speed_rad_s", "rad/s", "mean measured rotor speed during the burst"),
    Column("speed_rpm", "RPM", "the same in RPM"),
    Column("speed_std_rpm", "RPM", "standard deviation of the measured speed"),
    Column("cone_angle_rad", "rad", "mean tilt of the laser pattern's semi-axes (Eq. 5.24's phi)",
           analysis=True, accuracy="tilt"),
    Column("cone_angle_deg", "deg", "the same in degrees", analysis=True, accuracy="tilt"),
    Column("cone_angle_stderr_rad", "rad", "half the difference of the odd and even frames' angles",
           analysis=True, accuracy="tilt_stderr", accuracy_of="cone_angle_rad"),
    Column("cone_angle_stderr_deg", "deg", "the same in degrees", analysis=True, accuracy="tilt_stderr",
           accuracy_of="cone_angle_deg"),
    Column("verdict", "", "the burst analysis's verdict (ok, doubtful, failed)", accuracy="verdict"),
    Column("reasons", "", "why the verdict is not ok", accuracy="reasons"),
    Column("frames", "", "frames analysed"),
    Column("dropped", "", "frames the camera dropped during the burst"),
    Column("retaken", "", "the burst was taken again after a doubtful or failed one"),
    Column("model_cone_angle_rad", "rad", "the emulated camera's model plant angle (null on hardware)"),
)


EQ_5_97 = Hints(
    x="speed_rpm", y="phi_deg", x_name="rotor speed", x_unit="RPM", y_name="tilt amplitude phi",
    y_unit="deg", figure="Eq. 5.97", title="tilt amplitude phi [deg] against rotor speed [RPM] (strobe)",
    root="/eq5_97", fit="", residual="difference",
    report_title="Tilt amplitude, lateral amplitude and RC offset vs rotor speed (Eq. 5.97)",
    report_fits=(
        ReportFit("phi-cone-angle", "Eq. 5.24 on the tilt amplitude phi: tau_C and tau_S", "cone-angle",
                  "Tilt amplitude phi vs rotor speed (strobe, Eq. 5.97 / 5.24)", inertia=True, y="phi_rad"),
        ReportFit("beta-power-law", "Power law beta = a x^b", "power-law",
                  "Lateral amplitude beta vs rotor speed (strobe, Eq. 5.97)", x="speed_rpm", y="beta_mm"),
        ReportFit("delta-power-law", "Power law delta = a x^b (b near 0: delta does not depend on speed)",
                  "power-law", "RC offset delta vs rotor speed (strobe, Eq. 5.97)", x="speed_rpm",
                  y="delta_mm"),
    ),
    notes=("phi, beta and delta = beta / tan(phi) (Eq. 5.97) from the strobe analysis of each burst, the "
           "rotor and strobe frequencies from the strobe's status lines; error bars are the analysis's "
           "1-sigma from the residuals.",),
    also=(Series("beta_mm", "lateral amplitude beta", "mm"), Series("delta_mm", "RC offset delta", "mm")))

STROBE_SWEEP_ROW = (
    Column("step", "", "index of the step in the plan"),
    Column("target_rpm", "RPM", "the step's target speed"),
    Column("speed_rpm", "RPM", "mean measured rotor speed during the burst (tachometer)"),
    Column("phi_rad", "rad", "tilt amplitude phi (Eq. 5.97)", analysis=True, accuracy="phi"),
    Column("phi_stderr_rad", "rad", "its 1-sigma from the fit's residuals", analysis=True, accuracy="stderr"),
    Column("beta_mm", "mm", "lateral amplitude beta of the centre of mass across the magnet axis",
           analysis=True, accuracy="beta"),
    Column("beta_stderr_mm", "mm", "its 1-sigma", analysis=True, accuracy="stderr"),
    Column("delta_mm", "mm", "RC offset delta = beta / tan(phi) (Eq. 5.97)", analysis=True, accuracy="delta"),
    Column("delta_stderr_mm", "mm", "its 1-sigma", analysis=True, accuracy="stderr"),
    Column("verdict", "", "the analysis's verdict (ok, doubtful, failed), doubtful on a strobe flag",
           accuracy="verdict"),
    Column("speed_rad_s", "rad/s", "the same in rad/s"),
    Column("speed_std_rpm", "RPM", "standard deviation of the measured speed"),
    Column("offset_hz", "Hz", "the offset the strobe was set to (the apparent frequency)"),
    Column("divider", "", "flashes every divider-th revolution"),
    Column("rotor_hz", "Hz", "rotor frequency: mean of the strobe's locked status lines over the burst"),
    Column("strobe_hz", "Hz", "strobe frequency: the same lines' mean"),
    Column("apparent_hz", "Hz", "f_rot - m f_strobe of those lines"),
    Column("strobe_lines", "", "status lines read over the burst"),
    Column("strobe_flags", "", "flags in those lines (docs/reference/devices-strobe.md)"),
    Column("phi_deg", "deg", "phi in degrees", analysis=True, accuracy="phi"),
    Column("phi_stderr_deg", "deg", "its 1-sigma in degrees", analysis=True, accuracy="stderr"),
    Column("beta_px", "px", "beta in pixels (beta_mm = beta_px mm_per_px)", analysis=True, accuracy="beta"),
    Column("rc_offset_direction", "", "towards the body's top or bottom"),
    Column("analysed_apparent_hz", "Hz", "the apparent frequency the analysis used", analysis=True,
           accuracy="apparent_hz"),
    Column("reasons", "", "why the verdict is not ok", accuracy="reasons"),
    Column("frames", "", "frames analysed (0: a recorded clip)"),
    Column("dropped", "", "frames the camera dropped during the burst"),
    Column("retaken", "", "the burst was taken again after a doubtful or failed one"),
    Column("clip", "", "the recorded clip analysed (rigs without a camera)"),
    Column("model_phi_rad", "rad", "the emulated camera's model plant phi at the burst's speed "
                                   "(null on hardware)"),
    Column("model_beta_mm", "mm", "the model's beta (null on hardware)"),
    Column("model_delta_mm", "mm", "the model's delta (null on hardware)"),
)
