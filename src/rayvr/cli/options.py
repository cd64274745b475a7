"""Command-line values shared by the `rayvr` subcommands and the benchmarks: sizes and scenes."""
from __future__ import annotations

import re
from pathlib import Path

from ..errors import OptionError, did_you_mean

MAX_SIDE = 8192


def parse_size(text: str, option: str = "--size") -> tuple[int, int]:
    """'WIDTHxHEIGHT' in pixels, each side 1..8192."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", str(text))
    if not m or int(m.group(1)) < 1 or int(m.group(2)) < 1:
        raise OptionError(f"{option} {text}: expected WIDTHxHEIGHT in pixels, e.g. {option} 1440x1600")
    w, h = int(m.group(1)), int(m.group(2))
    if w > MAX_SIDE or h > MAX_SIDE:
        raise OptionError(f"{option} {text}: at most {MAX_SIDE} pixels a side; use a smaller size")
    return w, h


def load_scene_arg(spec: str | None, option: str = "scene"):
    """A glTF file (.gltf/.glb), a folder holding one, or a built-in scene by name (None: the
    Cornell box)."""
    from ..scene import builtin, load_scene

    if not spec:
        return builtin.cornell_box()
    path = Path(spec)
    if path.is_dir():
        found = sorted(path.glob("*.gl[tb]*")) or sorted(path.glob("glTF-Binary/*.glb")) or sorted(path.glob("glTF/*.gltf"))
        if not found:
            raise OptionError(f"{option} {spec}: the folder holds no .gltf or .glb file")
        return load_scene(found[0])
    if path.exists() or path.suffix.lower() in (".gltf", ".glb"):
        return load_scene(path)   # a missing file gets the loader's SceneError naming it
    if spec in builtin.SCENES:
        return builtin.SCENES[spec]()
    raise OptionError(f"{option} '{spec}': no such file and no built-in scene of that name"
                      f"{did_you_mean(spec, builtin.SCENES)}; built-ins: {', '.join(builtin.SCENES)}")
