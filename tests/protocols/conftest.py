import pytest

from labkit.emulators.plant import reset_plants


@pytest.fixture(autouse=True)
def fresh_plants():
    reset_plants()
    yield
    reset_plants()
