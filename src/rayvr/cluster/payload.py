"""A scene as it travels to the workers: through Ray's object store, never a shared file system.

- a glTF file: its bytes and the bytes of every file it references (buffers, images), written to
  a private folder on the worker and loaded there;
- a built-in scene: its recipe (the builtin's name and arguments);
- a `Scene` object: pickled as it is (edits made after loading travel with it).

Material effects set after loading (the CLI's `--effect`) travel with the first two as
{material: effect name} and are applied after the worker loads the scene.
"""
from __future__ import annotations

import dataclasses
import hashlib
import pickle
import shutil
import tempfile
from pathlib import Path, PurePosixPath
from urllib.parse import unquote

from ..errors import SceneError


@dataclasses.dataclass(frozen=True)
class ScenePayload:
    """What a worker needs to rebuild a scene; `key` names it in the workers' caches."""

    kind: str                      # "gltf", "builtin" or "pickle"
    name: str                      # the main file's name, the builtin's name, or the scene's
    files: dict = dataclasses.field(default_factory=dict)    # gltf: relative path -> bytes
    args: dict = dataclasses.field(default_factory=dict)     # builtin: keyword arguments
    blob: bytes = b""              # pickle: the pickled Scene
    effects: dict = dataclasses.field(default_factory=dict)  # material name -> effect name

    @classmethod
    def from_file(cls, path, effects: dict | None = None) -> "ScenePayload":
        """A .gltf/.glb file and the files it references inside its folder."""
        path = Path(path)
        try:
            files = {path.name: path.read_bytes()}
        except OSError as exc:
            raise SceneError(f"{path}: cannot read the scene ({exc.strerror or exc}); check the path") from None
        for uri in referenced_files(path):
            target = (path.parent / uri).resolve()
            if target.is_relative_to(path.parent.resolve()) and target.is_file():
                files[uri] = target.read_bytes()
            # anything else is left for the worker's loader to refuse with its own message
        return cls("gltf", path.name, files=files, effects=dict(effects or {}))

    @classmethod
    def builtin(cls, name: str, effects: dict | None = None, **args) -> "ScenePayload":
        """A built-in scene of rayvr.scenes by name, with its keyword arguments."""
        from ..scene import builtin

        if name not in builtin.SCENES:
            raise SceneError(f"no built-in scene '{name}'; built-ins: {', '.join(builtin.SCENES)}")
        return cls("builtin", name, args=dict(args), effects=dict(effects or {}))

    @classmethod
    def from_scene(cls, scene) -> "ScenePayload":
        """A Scene object, pickled."""
        return cls("pickle", scene.name, blob=pickle.dumps(scene, protocol=pickle.HIGHEST_PROTOCOL))

    @classmethod
    def of(cls, scene, effects: dict | None = None) -> "ScenePayload":
        """A payload from a ScenePayload, a Scene, a glTF path or a built-in name (None: the
        Cornell box), as `rayvr render` accepts them."""
        if isinstance(scene, ScenePayload):
            return scene
        if scene is None:
            return cls.builtin("cornell_box", effects)
        if isinstance(scene, (str, Path)):
            from ..scene import builtin

            path = Path(scene)
            if path.is_dir():
                found = sorted(path.glob("*.gl[tb]*")) or sorted(path.glob("glTF-Binary/*.glb")) or \
                    sorted(path.glob("glTF/*.gltf"))
                if not found:
                    raise SceneError(f"scene {scene}: the folder holds no .gltf or .glb file")
                return cls.from_file(found[0], effects)
            if isinstance(scene, str) and not path.exists() and scene in builtin.SCENES:
                return cls.builtin(scene, effects)
            return cls.from_file(path, effects)
        return cls.from_scene(scene)

    @property
    def key(self) -> str:
        """A digest of the content: equal payloads share one cache entry on a worker."""
        h = hashlib.sha256(repr((self.kind, self.name, sorted(self.args.items()),
                                 sorted(self.effects.items()))).encode())
        for rel in sorted(self.files):
            h.update(rel.encode() + b"\0" + hashlib.sha256(self.files[rel]).digest())
        h.update(self.blob)
        return h.hexdigest()[:24]

    def nbytes(self) -> int:
        return sum(len(b) for b in self.files.values()) + len(self.blob)

    def load(self):
        """The Scene (on a worker): unpickled, built, or written to a private folder and loaded."""
        if self.kind == "pickle":
            return pickle.loads(self.blob)
        if self.kind == "builtin":
            from ..scene import builtin

            scene = builtin.SCENES[self.name](**self.args)
        elif self.kind == "gltf":
            scene = self._load_gltf()
        else:
            raise SceneError(f"scene payload kind '{self.kind}' is unknown; use gltf, builtin or pickle")
        apply_effects(scene, self.effects)
        return scene

    def _load_gltf(self):
        from ..scene import load_scene

        folder = Path(tempfile.mkdtemp(prefix="rayvr-scene-"))
        try:
            for rel, data in self.files.items():
                parts = PurePosixPath(rel).parts
                if not parts or PurePosixPath(rel).is_absolute() or ".." in parts:
                    continue
                target = folder.joinpath(*parts)
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_bytes(data)
            return load_scene(folder / self.name)   # textures are decoded while loading
        finally:
            shutil.rmtree(folder, ignore_errors=True)


def referenced_files(path: Path) -> list[str]:
    """The relative URIs of buffers and images a glTF file names (data: URIs excluded)."""
    import pygltflib

    try:
        doc = pygltflib.GLTF2().load(str(path))
    except Exception:   # the driver's own load reports a broken file with the loader's message
        return []
    uris = [b.uri for b in (doc.buffers or [])] + [i.uri for i in (doc.images or [])]
    return [unquote(u) for u in uris if u and not u.startswith("data:") and "://" not in u]


def apply_effects(scene, effects: dict) -> None:
    """Set {material name: effect} on `scene` (names the payload carries)."""
    from ..materials.effect import Effect

    for name, effect in effects.items():
        scene.materials[name].effect = Effect.parse(effect, where=f"scene effect for '{name}'")


def effects_of(scene) -> dict:
    """{material name: effect name} of every material of `scene`."""
    return {m.name: m.effect.name for m in scene.materials}
