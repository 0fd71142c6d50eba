"""Every device test starts and ends with no shared plants (emulators of one test never see
the motors or forces another test left behind)."""

import pytest

from labkit.emulators.plant import reset_plants


@pytest.fixture(autouse=True)
def _fresh_plants():
    reset_plants()
    yield
    reset_plants()
