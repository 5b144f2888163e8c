import numpy as np
import pytest

from radioslam.config import RadioConfig


@pytest.fixture
def radio() -> RadioConfig:
    return RadioConfig()


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261122)
