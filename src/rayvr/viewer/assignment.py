"""Material effect assignments as JSON: {material: effect}, the viewer's save format, or a
`rayvr tune --report DIR` result (DIR/tune.json, whose "assignment" is the tuned choice)."""
from __future__ import annotations

import json
from pathlib import Path

from ..fileio import read_json
from ..errors import OptionError, did_you_mean
from ..materials.effect import Effect


def current_assignment(scene) -> dict[str, str]:
    """{material: effect name} of every material of the scene."""
    return {m.name: m.effect.name.lower() for m in scene.materials}


def save_assignment(path, scene) -> Path:
    """Write the scene's {material: effect} as JSON (atomically)."""
    from ..fileio import write_text

    path = Path(path)
    try:
        return write_text(path, json.dumps(current_assignment(scene), indent=2) + "\n")
    except OSError as exc:
        raise OptionError(f"{path}: cannot write it: {exc.strerror or exc}; choose a writable path") from None


def load_assignment(path, scene) -> dict[str, Effect]:
    """{material: Effect} from a JSON file (see the module docstring; a folder means its tune.json),
    checked against the scene's materials; OptionError naming the file and material otherwise."""
    path = Path(path)
    if path.is_dir():
        path = path / "tune.json"
    doc = read_json(path, str(path), what="the assignment",
                    hint="give a JSON file the viewer saved or a rayvr tune report's tune.json")
    if isinstance(doc, dict) and isinstance(doc.get("assignment"), dict):
        doc = doc["assignment"]
    if not isinstance(doc, dict) or not doc:
        raise OptionError(f"{path}: expected {{\"Material\": \"effect\", ...}} or a rayvr tune result "
                          f"with an \"assignment\"")
    names = scene.materials.names()
    out = {}
    for name, value in doc.items():
        if name not in names:
            raise OptionError(f"{path}: no material '{name}' in scene '{scene.name}'{did_you_mean(name, names)}; "
                              f"materials: {', '.join(names)}")
        out[name] = Effect.parse(value, where=f"{path}: {name}")
    return out


def apply_assignment(scene, assignment: dict) -> None:
    """Set each named material's effect (the Renderer recompiles when the set of effects changes)."""
    for name, effect in assignment.items():
        scene.materials[name].effect = Effect.parse(effect, where=f"material '{name}'")
