import numpy as np
import pytest

from radioslam.config import RadioConfig


@pytest.fixture
def radio() -> RadioConfig:
    return RadioConfig()


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261122)


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory):
    """The demo's run directory (paper-cnv, seed 1), made once for every test that reads it."""
    from radioslam.pipeline import RunOptions, run_scene

    out = tmp_path_factory.mktemp("demo")
    return out, run_scene("paper-cnv", out, RunOptions(seed=1))[1]
