"""labkit.model: the paper's PFR / MBS physics as pure, vectorised functions (SI units).

Modules: :mod:`dipole` (Eq. 4.1-4.5), :mod:`cone` (Eq. 5.5-5.35, 5.58, 5.62-5.68),
:mod:`stability` (Eq. 5.36-5.46), :mod:`pfr_force` (Eq. 5.70-5.93), :mod:`mbs`
(Eq. 5.85, 6.13-6.37), :mod:`rc_offset` (Eq. 5.97-5.102), :mod:`conical_dynamics`
(rigid axisymmetric dipole in a rotating field: equations of motion, co-rotating-frame
linear stability), :mod:`planar` (Eq. 5.56 periodic orbits), :mod:`one_dof` (Eq. 5.484),
:mod:`tilted_cone` (off-axis orbits of Fig. 5.4/5.6), :mod:`floator_equilibrium` (floator over
a tilted rotating dipole: co-rotating steady state and the Eq. 5.85 force parts).
See docs/reference/model.md.
"""

from labkit.model.cone import cone_angle, cone_angle_spin, cone_angles_axisymmetric
from labkit.model.dipole import dipole_field, dipole_force, dipole_torque
from labkit.model.mbs import equilibrium_distance, mbs_force, spin_for_speed
from labkit.model.pfr_force import cone_angle_at_distance, dipole_constant, pfr_force
from labkit.model.rc_offset import offset_from_amplitudes
from labkit.model.stability import criterion_holds, min_static_torque

__all__ = [
    "cone_angle", "cone_angle_at_distance", "cone_angle_spin", "cone_angles_axisymmetric", "criterion_holds",
    "dipole_constant", "dipole_field", "dipole_force", "dipole_torque", "equilibrium_distance", "mbs_force",
    "min_static_torque", "offset_from_amplitudes", "pfr_force", "spin_for_speed",
]
