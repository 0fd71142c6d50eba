"""labkit.model: the paper's PFR / MBS physics as pure, vectorised functions (SI units).

Modules: :mod:`dipole` (Eq. 4.1-4.5), :mod:`cone` (Eq. 5.5-5.35, 5.58, 5.62-5.68),
:mod:`stability` (Eq. 5.36-5.46), :mod:`pfr_force` (Eq. 5.70-5.93), :mod:`mbs`
(Eq. 5.85, 6.13-6.37), :mod:`rc_offset` (Eq. 5.97-5.102), :mod:`conical_dynamics`
(rigid axisymmetric dipole in a rotating field: equations of motion, co-rotating-frame
linear stability), :mod:`planar` (Eq. 5.56 periodic orbits), :mod:`one_dof` (Eq. 5.484),
:mod:`tilted_cone` (off-axis orbits of Fig. 5.4/5.6), :mod:`floator_equilibrium` (floator over
a tilted rotating dipole: co-rotating steady state and the Eq. 5.85 force parts).
See docs/model.md.
"""
