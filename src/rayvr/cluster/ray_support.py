"""Ray, imported only when a cluster job runs: rayvr and rayvr.cluster import without it."""
from __future__ import annotations

from ..errors import ClusterError

INSTALL_HINT = "pip install 'rayvr[cluster]'"


def require_ray(what: str = "rayvr.cluster"):
    """The `ray` module, or ClusterError naming `what` and the install command."""
    try:
        import ray
    except ImportError:
        raise ClusterError(f"{what} needs the cluster extra: {INSTALL_HINT}") from None
    return ray


def have_ray() -> bool:
    """Whether Ray is installed here (without importing it)."""
    import importlib.util

    try:
        return importlib.util.find_spec("ray") is not None
    except ValueError:   # sys.modules["ray"] is None: imports of it are blocked
        return False
