"""RC offset (Eq. 5.97-5.102): the shape lengths the paper prints and the small-angle relations."""

import numpy as np
import pytest

from labkit.model.rc_offset import (
    angular_amplitude,
    force_torque_ratio,
    lateral_amplitude,
    offset_from_amplitudes,
    offset_from_loads,
    offset_pole_model,
    shape_length,
)


@pytest.mark.parametrize("inertia_over_mh2,printed", [(1 / 12, 1 / 6), (1 / 6, 1 / 3), (7 / 48, 7 / 24)])
def test_shape_length_for_rod_cube_cylinder(inertia_over_mh2, printed):
    """W = 2I/(hm): rod (I = m h^2/12), cube (m h^2/6), cylinder d = h (I_R = 7 m h^2/48)."""
    h, m = 0.01, 0.005
    assert shape_length(inertia_over_mh2 * m * h**2, h, m) == pytest.approx(printed * h)


def test_offset_is_ratio_of_driven_amplitudes():
    f, t, m, inertia, w = 0.5, 1e-4, 0.006, 1e-7, 600.0
    beta, phi = lateral_amplitude(f, m, w), angular_amplitude(t, inertia, w)
    assert offset_from_loads(f, t, inertia, m) == pytest.approx(beta / phi)
    assert offset_from_amplitudes(beta, np.arctan(phi)) == pytest.approx(beta / phi)


def test_pole_model_is_eq_5_100_with_eq_5_101_and_bounded_for_antiparallel_forces():
    inertia, h, m = 1e-7, 0.01, 0.006
    for k in (-0.2, -1.0, -5.0):
        delta = offset_pole_model(k, inertia, h, m)
        assert abs(delta) < shape_length(inertia, h, m)
        assert delta == pytest.approx(force_torque_ratio(h, k) * inertia / m)
