"""What the viewer needs before it opens a window: the `viewer` extra and a display.

glfw and imgui-bundle are imported here, on first use, and nowhere at `import rayvr` time.
Each check fails with one ViewerError line that says what is missing and how to get it.
"""
from __future__ import annotations

import importlib
import os
import sys

from ..errors import ViewerError

EXTRA_HINT = "pip install 'rayvr[viewer]'"
# import name -> PyPI name
EXTRA_MODULES = {"glfw": "glfw", "imgui_bundle": "imgui-bundle"}


def require_extra() -> None:
    """Import glfw and imgui-bundle, or raise ViewerError naming the one that is missing."""
    for module, package in EXTRA_MODULES.items():
        try:
            importlib.import_module(module)
        except ImportError as exc:
            raise ViewerError(f"rayvr view needs the viewer extra ({package} is missing: {exc}): "
                              f"{EXTRA_HINT}") from None


def require_display() -> None:
    """On Linux and the BSDs, a window needs an X server: DISPLAY must be set."""
    if sys.platform.startswith(("linux", "freebsd", "openbsd", "netbsd")) and not os.environ.get("DISPLAY"):
        wayland = " (WAYLAND_DISPLAY is set, but rayvr's window needs X11: start Xwayland)" \
            if os.environ.get("WAYLAND_DISPLAY") else ""
        raise ViewerError(f"rayvr view needs a display: DISPLAY is not set{wayland} "
                          f"(run under Xvfb, or use rayvr render)")


def require_window_support() -> None:
    """Both checks, the extra first: what a window needs."""
    require_extra()
    require_display()
