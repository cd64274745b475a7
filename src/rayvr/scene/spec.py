"""A scene as a user names one: a glTF file, a folder holding one, or a built-in scene's name
(the command line's SCENE, the viewer's `scene=`)."""
from __future__ import annotations

import sys
import warnings
from pathlib import Path

from ..errors import OptionError, SceneWarning, did_you_mean


def load_scene_spec(spec: str | None, option: str = "scene", print_warnings: bool = True):
    """A glTF file (.gltf/.glb), a folder holding one, or a built-in scene by name (None: the
    Cornell box). The loader's warnings go to stderr, one line each, unless `print_warnings`
    is false (they stay in `scene.warnings`)."""
    from . import builtin

    if not spec:
        return builtin.cornell_box()
    path = Path(spec)
    if path.is_dir():
        found = sorted(path.glob("*.gl[tb]*")) or sorted(path.glob("glTF-Binary/*.glb")) or sorted(path.glob("glTF/*.gltf"))
        if not found:
            raise OptionError(f"{option} {spec}: the folder holds no .gltf or .glb file")
        return _load_file(found[0], print_warnings)
    if path.exists() or path.suffix.lower() in (".gltf", ".glb"):
        return _load_file(path, print_warnings)   # a missing file gets the loader's SceneError naming it
    if spec in builtin.SCENES:
        return builtin.SCENES[spec]()
    raise OptionError(f"{option} '{spec}': no such file and no built-in scene of that name"
                      f"{did_you_mean(spec, builtin.SCENES)}; built-ins: {', '.join(builtin.SCENES)}")


def _load_file(path: Path, print_warnings: bool):
    """Load a glTF file; its warnings go to stderr once, one line each (not through `warnings`)."""
    from . import load_scene

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SceneWarning)
        scene = load_scene(path)
    for line in scene.warnings if print_warnings else ():
        print(f"rayvr: warning: {line}", file=sys.stderr)
    return scene
