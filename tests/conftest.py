"""Shared fixtures: a seeded ``rng``, hypothesis profiles, and the run's environment in the header.

Every random test takes its generator from the ``rng`` fixture (seeded per test from its node id,
so one test's draws never depend on which other tests ran) or seeds ``np.random.default_rng``
itself with a documented seed; nothing uses numpy's global state.

Hypothesis profiles (as astropy does): ``ci`` (the default here: derandomized, so a run is
reproducible) and ``fuzz`` (many more examples; ``pytest --hypothesis-profile=fuzz``).
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import sys

import numpy as np
import pytest

try:
    from hypothesis import HealthCheck, settings
except ImportError:  # the test extra installs it; tests that need it import it themselves
    settings = None
else:
    settings.register_profile("ci", derandomize=True, deadline=None,
                              suppress_health_check=[HealthCheck.too_slow])
    settings.register_profile("fuzz", max_examples=5000, deadline=None,
                              suppress_health_check=[HealthCheck.too_slow])
    settings.load_profile("ci")


@pytest.fixture
def rng(request) -> np.random.Generator:
    """A generator seeded from the test's node id: fixed for a test, different between tests."""
    seed = int.from_bytes(hashlib.sha256(request.node.nodeid.encode()).digest()[:8], "little")
    return np.random.default_rng(seed)


def pytest_report_header(config) -> list[str]:
    """Which interpreter and which releases this run used (CI makes a fresh environment)."""
    versions = []
    for name in ("numpy", "scipy", "matplotlib", "dask", "distributed", "pyarrow", "h5py",
                 "rosbags", "PyYAML", "allantools", "hypothesis"):
        try:
            versions.append(f"{name} {importlib.metadata.version(name)}")
        except importlib.metadata.PackageNotFoundError:
            versions.append(f"{name} absent")
    return [f"sigmatau environment: {sys.prefix}", "releases: " + ", ".join(versions)]
