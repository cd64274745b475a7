"""Shared fixtures: one headless GL context for the whole run (llvmpipe on CI)."""
import os

import pytest

os.environ.setdefault("RAYVR_GL_BACKEND", "egl")


@pytest.fixture(scope="session")
def gpu():
    from rayvr.gpu import get_context

    return get_context()


@pytest.fixture(scope="session")
def gl(gpu):
    return gpu.gl


@pytest.fixture(scope="session")
def cluster():
    """A local Ray (2 CPUs) with two rayvr cluster workers on llvmpipe, shared by the cluster
    tests and shut down after them; the tests skip where Ray is not installed."""
    ray = pytest.importorskip("ray", reason="the cluster tests need Ray: pip install -e '.[test,cluster]'")
    from rayvr.cluster import Cluster

    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, logging_level="error",
             object_store_memory=256 * 1024 * 1024)
    c = Cluster(2)
    yield c
    c.close()
    ray.shutdown()
