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
