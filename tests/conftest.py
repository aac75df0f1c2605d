"""Shared test configuration (owned by the lead; do not edit in feature work)."""

import os

import matplotlib
import numpy as np
import pytest
from hypothesis import HealthCheck, settings

matplotlib.use("Agg")

settings.register_profile(
    "default", deadline=None, max_examples=30, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
settings.register_profile(
    "ci", deadline=None, max_examples=30, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
settings.load_profile("ci" if os.environ.get("CI") else "default")


@pytest.fixture
def rng():
    """A seeded generator: every random test is reproducible."""
    return np.random.default_rng(20261122)


#: Appendix 2 initial data (y, x, z) and parameters
APPENDIX2_X0 = np.array([-2.4, -0.6, -1.2, -2.19, 0.89, 1.34, 1.0, 0.0, 0.0])
APPENDIX2_B = 1.0
APPENDIX2_ETA = 5 + 0.1j
