"""The bad-input corpus: malformed and hostile glTF/GLB files generated in code, fed through the
CLI (`render`, and the GLB truncations through `tune` and `graph show --scene` too). Each case
must give exit code 2 and one `rayvr: error:` line naming the file and the field, write
nothing, and open nothing outside the scene folder (every open is spied on)."""
import builtins
import io
import json
import os
import struct
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from rayvr.cli.main import main
from test_scene_gltf import QUAD_P, base_doc

GLB_JSON, GLB_BIN = 0x4E4F534A, 0x004E4942


def glb_bytes(doc, blob, patch=None) -> bytes:
    """A GLB of `doc` (buffers[0] becomes the BIN chunk) and `blob`."""
    doc = json.loads(json.dumps(doc))
    doc["buffers"][0].pop("uri", None)
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    blob = blob + b"\0" * (-len(blob) % 4)
    body = struct.pack("<II", len(text), GLB_JSON) + text + struct.pack("<II", len(blob), GLB_BIN) + blob
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def valid_glb() -> bytes:
    return glb_bytes(*base_doc())


def truncated(n: int, fix_length: bool = False) -> bytes:
    data = valid_glb()[:n]
    if fix_length and n >= 12:
        data = data[:8] + struct.pack("<I", n) + data[12:]
    return data


JSON_END = 20 + struct.unpack_from("<I", valid_glb(), 12)[0]   # offset of the BIN chunk header

# --- GLB container cases: (id, bytes, words the error line must hold) ---------------------------
GLB_CASES = [
    ("empty", b"", ["GLB header", "empty"]),
    ("10 bytes", truncated(10), ["GLB header", "10 bytes", "needs 12"]),
    ("header only", truncated(12, True), ["GLB chunk 0", "missing"]),
    ("header, length not patched", truncated(40), ["GLB header.length", "truncated"]),
    ("cut in chunk 0 header", truncated(16, True), ["GLB chunk 0 header", "truncated"]),
    ("cut in JSON chunk", truncated(60, True), ["GLB chunk 0 (JSON).chunkLength", "truncated"]),
    ("cut after JSON chunk", truncated(JSON_END, True), ["buffers[0]", "no GLB binary chunk"]),
    ("cut in BIN chunk header", truncated(JSON_END + 4, True), ["GLB chunk 1 header", "truncated"]),
    ("cut in BIN chunk data", truncated(JSON_END + 20, True), ["GLB chunk 1 (BIN).chunkLength", "truncated"]),
    ("wrong magic", b"glTX" + valid_glb()[4:], ["GLB header.magic"]),
    ("version 1", valid_glb()[:4] + struct.pack("<I", 1) + valid_glb()[8:], ["GLB header.version", "1"]),
    ("random bytes", np.random.default_rng(1).integers(0, 256, 4096, dtype=np.uint8).tobytes(),
     ["GLB header.magic"]),
    ("text file", b"this is not a model\n" * 3, ["GLB header.magic"]),
    ("JSON named .glb", json.dumps(base_doc()[0]).encode(), ["GLB header.magic", "name it .gltf"]),
]


def _glb_variant(mutate) -> bytes:
    data = bytearray(valid_glb())
    mutate(data)
    return bytes(data)


def _glb_of(*chunks) -> bytes:
    """A GLB of the given (chunk type, data) pairs, each padded to 4 bytes."""
    body = b""
    for kind, data in chunks:
        data += b" " * (-len(data) % 4)
        body += struct.pack("<II", len(data), kind) + data
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


GLB_CASES += [
    ("chunk length unaligned", _glb_variant(lambda d: d.__setitem__(slice(12, 16), struct.pack("<I", 5))),
     ["GLB chunk 0 (JSON).chunkLength", "multiple of 4"]),
    ("BIN chunk first", valid_glb()[:16] + struct.pack("<I", GLB_BIN) + valid_glb()[20:],
     ["GLB chunk 0 (BIN)", "first chunk must be JSON"]),
    ("two JSON chunks", _glb_of((GLB_JSON, b'{"asset":{"version":"2.0"}}'), (GLB_JSON, b"{}")),
     ["GLB chunk 1 (JSON)", "a second JSON chunk"]),
    ("JSON chunk not UTF-8", _glb_of((GLB_JSON, b'{"asset": "\xff\xfe"}')), ["GLB chunk 0 (JSON)", "not UTF-8"]),
    ("JSON chunk broken", _glb_of((GLB_JSON, b'{"asset": {"version": "2.0"')),
     ["GLB chunk 0 (JSON)", "broken glTF JSON"]),
    ("BIN shorter than byteLength", glb_bytes(base_doc()[0], base_doc()[1][:40]),
     ["buffers[0].byteLength", "truncated"]),
]


# --- .gltf document cases: (id, mutate(doc, folder) -> None, words) ------------------------------
def _set(path, value):
    def mutate(doc, folder):
        *keys, last = path
        obj = doc
        for k in keys:
            obj = obj[k]
        obj[last] = value
    return mutate


def _merge(extra):
    def mutate(doc, folder):
        for key, value in extra.items():
            doc[key] = value
    return mutate


def _camera(perspective):
    return _merge({"cameras": [{"type": "perspective", "perspective": perspective}],
                   "nodes": [{"name": "Q", "mesh": 0}, {"camera": 0}], "scenes": [{"nodes": [0, 1]}]})


def _light(light, node_light=0):
    return _merge({"extensionsUsed": ["KHR_lights_punctual"],
                   "extensions": {"KHR_lights_punctual": {"lights": [light]}},
                   "nodes": [{"name": "Q", "mesh": 0}, {"extensions": {"KHR_lights_punctual": {"light": node_light}}}],
                   "scenes": [{"nodes": [0, 1]}]})


def _material_ext(name, body):
    def mutate(doc, folder):
        doc["extensionsUsed"] = [name]
        doc["materials"][0]["extensions"] = {name: body}
    return mutate


def _nodes(nodes, roots=(0,)):
    return _merge({"nodes": nodes, "scenes": [{"nodes": list(roots)}]})


def _uri(uri):
    return _set(("buffers", 0, "uri"), uri)


def _blob_edit(edit):
    """Rewrite data.bin through `edit(positions, indices, uvs) -> bytes`."""
    def mutate(doc, folder):
        doc_, blob = base_doc()
        p, i, uv = np.frombuffer(blob[:48], np.float32).reshape(4, 3).copy(), \
            np.frombuffer(blob[48:72], np.uint32).copy(), np.frombuffer(blob[72:], np.float32).copy()
        (folder / "data.bin").write_bytes(edit(p, i, uv))
    return mutate


def _sparse(indices, count=None):
    """accessors[0] gets a sparse part overriding `indices` (uint32 in a new buffer view)."""
    def mutate(doc, folder):
        _, blob = base_doc()
        idx = np.asarray(indices, np.uint32).tobytes()
        values = np.zeros((len(indices), 3), np.float32).tobytes()
        (folder / "data.bin").write_bytes(blob + idx + values)
        doc["buffers"][0]["byteLength"] = len(blob) + len(idx) + len(values)
        doc["bufferViews"] += [{"buffer": 0, "byteOffset": len(blob), "byteLength": len(idx)},
                               {"buffer": 0, "byteOffset": len(blob) + len(idx), "byteLength": len(values)}]
        doc["accessors"][0]["sparse"] = {"count": count or len(indices),
                                         "indices": {"bufferView": 3, "componentType": 5125},
                                         "values": {"bufferView": 4}}
    return mutate


def _symlink(target):
    def mutate(doc, folder):
        (folder / "data.bin").unlink()
        (folder / "data.bin").symlink_to(target)
    return mutate


def _fifo(doc, folder):
    (folder / "data.bin").unlink()
    os.mkfifo(folder / "data.bin")


def _raw(text: bytes):
    def mutate(doc, folder):
        doc.clear()
        doc["__raw__"] = text
    return mutate


def _nan_positions(p, i, uv):
    p[2, 1] = np.nan
    return p.tobytes() + i.tobytes() + uv.tobytes()


def _bad_index(p, i, uv):
    i[4] = 9
    return p.tobytes() + i.tobytes() + uv.tobytes()


def _delete(path):
    def mutate(doc, folder):
        *keys, last = path
        obj = doc
        for k in keys:
            obj = obj[k]
        del obj[last]
    return mutate


GLTF_CASES = [
    ("empty gltf", _raw(b""), ["the file is empty"]),
    ("JSON array root", _raw(b"[1, 2]"), ["JSON root is a list"]),
    ("NaN in a matrix", _raw(b'{"asset":{"version":"2.0"},"nodes":[{"matrix":[NaN,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]}]}'),
     ["broken glTF JSON", "NaN"]),
    ("Infinity by overflow", _raw(b'{"asset":{"version":"2.0"},"nodes":[{"translation":[1e999,0,0]}]}'),
     ["broken glTF JSON", "1e999"]),
    ("deep nesting", _raw(b'{"asset":{"version":"2.0"},"extras":' + b"[" * 100000 + b"]" * 100000 + b"}"),
     ["nests too deeply"]),
    ("JSON not UTF-8", _raw(b'{"asset":{"version":"2.0","generator":"\xff"}}'), ["not UTF-8"]),
    ("no asset", _delete(("asset",)), ["asset: missing"]),
    ("asset version 3.0", _set(("asset", "version"), "3.0"), ["asset.version", "not glTF 2.x"]),
    ("asset version a number", _set(("asset", "version"), 2), ["asset.version", "not a string"]),
    ("asset minVersion 2.1", _set(("asset", "minVersion"), "2.1"), ["asset.minVersion", "glTF 2.1 reader"]),
    ("required extension unimplemented", _merge({"extensionsUsed": ["KHR_draco_mesh_compression"],
                                                 "extensionsRequired": ["KHR_draco_mesh_compression"]}),
     ["extensionsRequired[0]", "KHR_draco_mesh_compression", "does not implement"]),
    ("required but not used", _merge({"extensionsRequired": ["KHR_lights_punctual"]}),
     ["extensionsRequired[0]", "not listed in extensionsUsed"]),
    ("extension not declared", _set(("materials", 0, "extensions"), {"KHR_materials_ior": {"ior": 1.4}}),
     ["materials[0].extensions.KHR_materials_ior", "not declared in extensionsUsed"]),
    ("camera yfov 0", _camera({"yfov": 0, "znear": 0.1}), ["cameras[0].perspective.yfov", "out of range"]),
    ("camera yfov negative", _camera({"yfov": -0.5, "znear": 0.1}), ["cameras[0].perspective.yfov"]),
    ("camera znear 0", _camera({"yfov": 0.8, "znear": 0}), ["cameras[0].perspective.znear", "out of range"]),
    ("camera zfar <= znear", _camera({"yfov": 0.8, "znear": 1.0, "zfar": 0.5}),
     ["cameras[0].perspective.zfar", "not greater than znear"]),
    ("camera without yfov", _camera({"znear": 0.1}), ["cameras[0].perspective.yfov: missing"]),
    ("roughness 1.5", _set(("materials", 0, "pbrMetallicRoughness", "roughnessFactor"), 1.5),
     ["materials[0].pbrMetallicRoughness.roughnessFactor", "1.5 is out of range [0, 1]"]),
    ("metallic negative", _set(("materials", 0, "pbrMetallicRoughness", "metallicFactor"), -0.1),
     ["materials[0].pbrMetallicRoughness.metallicFactor", "out of range"]),
    ("base colour of 3", _set(("materials", 0, "pbrMetallicRoughness", "baseColorFactor"), [1, 0, 0]),
     ["materials[0].pbrMetallicRoughness.baseColorFactor", "needs 4"]),
    ("emissive factor 2", _set(("materials", 0, "emissiveFactor"), [2, 0, 0]),
     ["materials[0].emissiveFactor[0]", "out of range"]),
    ("emissive strength negative", _material_ext("KHR_materials_emissive_strength", {"emissiveStrength": -1}),
     ["materials[0].extensions.KHR_materials_emissive_strength.emissiveStrength", "out of range"]),
    ("transmission 2", _material_ext("KHR_materials_transmission", {"transmissionFactor": 2}),
     ["KHR_materials_transmission.transmissionFactor"]),
    ("ior 0.5", _material_ext("KHR_materials_ior", {"ior": 0.5}), ["KHR_materials_ior.ior", "0 or a value >= 1"]),
    ("light intensity negative", _light({"type": "point", "intensity": -5}),
     ["extensions.KHR_lights_punctual.lights[0].intensity", "out of range"]),
    ("light of unknown type", _light({"type": "area"}), ["extensions.KHR_lights_punctual.lights[0].type", "area"]),
    ("spot cone inverted", _light({"type": "spot", "spot": {"innerConeAngle": 0.6, "outerConeAngle": 0.4}}),
     ["lights[0].spot.innerConeAngle", "out of range"]),
    ("node light out of range", _light({"type": "point"}, node_light=3),
     ["nodes[1].extensions.KHR_lights_punctual.light", "light 3 does not exist"]),
    ("materials not an array", _set(("materials",), {"name": "Red"}), ["materials", "not an array"]),
    ("material not an object", _set(("materials",), ["Red"]), ["materials[0]", "not an object"]),
    ("count is a string", _set(("accessors", 0, "count"), "4"), ["accessors[0].count", "not an integer"]),
    ("count is a float", _set(("accessors", 0, "count"), 4.0), ["accessors[0].count", "not an integer"]),
    ("bufferView out of range", _set(("accessors", 0, "bufferView"), 7),
     ["accessors[0].bufferView", "bufferView 7 out of range"]),
    ("POSITION accessor out of range", _set(("meshes", 0, "primitives", 0, "attributes", "POSITION"), 9),
     ["meshes[0].primitives[0].attributes.POSITION", "accessor 9 out of range"]),
    ("huge count in a bufferView", _set(("accessors", 0, "count"), 10 ** 12),
     ["accessors[0]", "run past the end", "attributes.POSITION"]),
    ("huge count without bufferView", _merge({"accessors": base_doc()[0]["accessors"] + [
        {"componentType": 5126, "count": 10 ** 11, "type": "VEC3"}]}), ["accessors[3].count", "refused"]),
    ("huge buffer byteLength", _set(("buffers", 0, "byteLength"), 10 ** 15), ["buffers[0].uri", "fewer than"]),
    ("bufferView past its buffer", _set(("bufferViews", 2, "byteLength"), 4096),
     ["bufferViews[2]", "do not fit buffers[0]"]),
    ("byteStride 3", _set(("bufferViews", 0, "byteStride"), 3), ["bufferViews[0].byteStride", "out of range"]),
    ("byteOffset unaligned", _set(("accessors", 2, "byteOffset"), 2), ["accessors[2].byteOffset", "multiple"]),
    ("componentType 1234", _set(("accessors", 0, "componentType"), 1234), ["accessors[0].componentType", "1234"]),
    ("POSITION is VEC2", _merge({"accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC2",
                                                "min": [0, 0], "max": [1, 1]}] + base_doc()[0]["accessors"][1:]}),
     ["attributes.POSITION", "accessors[0] is VEC2 FLOAT", "must be VEC3"]),
    ("POSITION without bounds", _delete(("accessors", 0, "min")), ["attributes.POSITION", "no min and max"]),
    ("attributes of different counts", _set(("accessors", 2, "count"), 3), ["attributes", "different counts"]),
    ("float indices", _set(("accessors", 1, "componentType"), 5126), ["primitives[0].indices", "indices must be"]),
    ("primitive mode 9", _set(("meshes", 0, "primitives", 0, "mode"), 9), ["primitives[0].mode", "9"]),
    ("mesh without primitives", _delete(("meshes", 0, "primitives")), ["meshes[0].primitives: missing"]),
    ("primitive without attributes", _delete(("meshes", 0, "primitives", 0, "attributes")),
     ["meshes[0].primitives[0].attributes: missing"]),
    ("buffer without byteLength", _delete(("buffers", 0, "byteLength")), ["buffers[0].byteLength: missing"]),
    ("NaN positions", _blob_edit(_nan_positions), ["meshes[0].primitives[0].attributes.POSITION", "NaN"]),
    ("vertex index out of range", _blob_edit(_bad_index), ["meshes[0].primitives[0].indices", "index 9 out of range"]),
    ("non-affine matrix", _nodes([{"mesh": 0, "matrix": [1, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}]),
     ["nodes[0].matrix", "affine"]),
    ("matrix and TRS", _nodes([{"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1],
                                "translation": [1, 0, 0]}]), ["nodes[0]", "both a matrix and"]),
    ("rotation not unit", _nodes([{"mesh": 0, "rotation": [0, 0, 0, 0.5]}]), ["nodes[0].rotation", "unit quaternion"]),
    ("node cycle", _nodes([{"mesh": 0}, {"children": [2]}, {"children": [1]}]), ["children", "cycle"]),
    ("node lists itself", _nodes([{"mesh": 0, "children": [0]}]), ["nodes[0].children", "lists itself"]),
    ("node under two parents", _nodes([{"children": [2]}, {"children": [2]}, {"mesh": 0}], roots=(0, 1)),
     ["nodes[1].children", "node 2 already has parent nodes[0]"]),
    ("child out of range", _nodes([{"mesh": 0, "children": [9]}]), ["nodes[0].children[0]", "node 9 out of range"]),
    ("scene lists a child", _nodes([{"children": [1]}, {"mesh": 0}], roots=(0, 1)),
     ["scenes[0].nodes[1]", "not a root"]),
    ("scene out of range", _set(("scene",), 4), ["scene", "scene 4 out of range"]),
    ("sparse indices not increasing", _sparse([2, 1]), ["sparse", "indices", "must increase"]),
    ("sparse index out of range", _sparse([1, 7]), ["sparse", "indices", "index 7 out of range for 4"]),
    ("sparse count above count", _sparse([0, 1, 2, 3, 4]), ["accessors[0].sparse.count", "more elements"]),
    ("texture source out of range", _merge({"textures": [{"source": 3}]}),
     ["textures[0].source", "image 3 out of range"]),
    ("material texture out of range", _set(("materials", 0, "pbrMetallicRoughness", "baseColorTexture"), {"index": 5}),
     ["baseColorTexture.index", "texture 5 out of range"]),
    ("image undecodable", _merge({"images": [{"uri": "data:image/png;base64,bm90IGEgcG5n"}],
                                  "textures": [{"source": 0}]}), ["images[0]", "cannot be decoded"]),
    ("image with uri and bufferView", _merge({"images": [{"uri": "a.png", "bufferView": 0, "mimeType": "image/png"}]}),
     ["images[0]", "exactly one of uri and bufferView"]),
    # URIs: every one of these is refused before anything outside the folder is opened
    ("uri to the parent folder", _uri("../secret.bin"), ["buffers[0].uri", "outside the scene folder"]),
    ("uri through a subfolder", _uri("sub/../../secret.bin"), ["buffers[0].uri", "outside the scene folder"]),
    ("absolute uri", _uri("/etc/passwd"), ["buffers[0].uri", "outside the scene folder"]),
    ("uri /dev/zero", _uri("/dev/zero"), ["buffers[0].uri", "outside the scene folder"]),
    ("uri /dev/stdin", _uri("/dev/stdin"), ["buffers[0].uri", "outside the scene folder"]),
    ("file:// uri", _uri("file:///dev/zero"), ["buffers[0].uri", "absolute path or URL"]),
    ("http uri", _uri("http://example.com/data.bin"), ["buffers[0].uri", "absolute path or URL"]),
    ("percent-encoded escape", _uri("%2E%2E/secret.bin"), ["buffers[0].uri", "outside the scene folder"]),
    ("symlink to /dev/zero", _symlink("/dev/zero"), ["buffers[0].uri", "outside the scene folder"]),
    ("symlink outside", _symlink("../secret.bin"), ["buffers[0].uri", "outside the scene folder"]),
    ("FIFO in the folder", _fifo, ["buffers[0].uri", "not a regular file"]),
    ("image uri outside", _merge({"images": [{"uri": "../secret.bin"}], "textures": [{"source": 0}]}),
     ["images[0].uri", "outside the scene folder"]),
    ("data uri not base64", _uri("data:application/octet-stream,abcd"), ["buffers[0].uri", "not base64"]),
    ("data uri bad base64", _uri("data:application/octet-stream;base64,@@@@"), ["buffers[0].uri", "bad data URI"]),
    ("data uri short", _uri("data:application/octet-stream;base64,AAAA"), ["buffers[0].uri", "holds 3 bytes"]),
    ("data uri of the wrong type", _uri("data:text/plain;base64,AAAA"), ["buffers[0].uri", "text/plain"]),
]


def _build(tmp_path, mutate):
    """The scene folder (scene.gltf, data.bin) with `mutate` applied, and a secret beside it."""
    folder = tmp_path / "scene"
    folder.mkdir()
    (tmp_path / "secret.bin").write_bytes(b"\1" * 4096)
    doc, blob = base_doc()
    (folder / "data.bin").write_bytes(blob)
    mutate(doc, folder)
    path = folder / "scene.gltf"
    path.write_bytes(doc["__raw__"] if "__raw__" in doc else json.dumps(doc).encode())
    return path


class OpenSpy:
    """Records every path opened for reading through open(), io.open and os.open (writes are
    checked by listing the folders afterwards)."""

    def __init__(self, monkeypatch):
        self.paths = []
        for module, name in ((builtins, "open"), (io, "open"), (os, "open")):
            original = getattr(module, name)
            monkeypatch.setattr(module, name, self._wrap(original, module is os))

    def _wrap(self, original, flags_api: bool):
        def spy(file, *args, **kwargs):
            mode = args[0] if args else kwargs.get("flags" if flags_api else "mode", 0 if flags_api else "r")
            reads = (mode & (os.O_WRONLY | os.O_CREAT)) == 0 if flags_api else ("r" in mode or "+" in mode)
            # os.devnull: subprocess's stdin for the driver lookup (ldconfig -p) on the first GL context
            if reads and isinstance(file, (str, bytes, os.PathLike)) and os.fsdecode(file) != os.devnull:
                self.paths.append(Path(os.fsdecode(file)))
            return original(file, *args, **kwargs)
        return spy

    def outside(self, *folders) -> list[Path]:
        """Opened paths outside `folders` and outside Python's own files (lazy imports)."""
        import rayvr

        inside = [Path(os.path.abspath(f)) for f in folders] + [
            Path(p).resolve() for p in (sys.prefix, sys.base_prefix, Path(rayvr.__file__).parent)]
        return [p for p in self.paths
                if not any(Path(os.path.abspath(p)).is_relative_to(f) for f in inside)]


def _expect_refusal(argv, path, words, capsys, monkeypatch, tmp_path, extra_allowed=()):
    before = sorted(p.name for p in path.parent.iterdir())
    spy = OpenSpy(monkeypatch)
    code = main(argv)
    monkeypatch.undo()
    out, err = capsys.readouterr()
    assert code == 2, (out, err)
    line = err.strip()
    assert "\n" not in line and line.startswith("rayvr: error:"), err
    assert path.name in line, line
    for w in words:
        assert w in line, f"{w!r} not in {line!r}"
    assert not (tmp_path / "out").exists()                              # nothing written
    assert sorted(p.name for p in path.parent.iterdir()) == before      # no temporaries either
    assert spy.outside(path.parent, tmp_path / "out", *extra_allowed) == []
    assert tmp_path / "secret.bin" not in spy.paths


def _render_argv(path, tmp_path):
    return ["render", str(path), "--size", "8x8", "--out", str(tmp_path / "out" / "x.png")]


@pytest.mark.parametrize("name, data, words", GLB_CASES, ids=[c[0] for c in GLB_CASES])
def test_broken_glb_through_render(tmp_path, capsys, monkeypatch, name, data, words):
    folder = tmp_path / "scene"
    folder.mkdir()
    path = folder / "scene.glb"
    path.write_bytes(data)
    _expect_refusal(_render_argv(path, tmp_path), path, words, capsys, monkeypatch, tmp_path)


@pytest.mark.parametrize("command", ["tune", "graph"])
@pytest.mark.parametrize("name, data, words", GLB_CASES[:9], ids=[c[0] for c in GLB_CASES[:9]])
def test_broken_glb_through_tune_and_graph_show(tmp_path, capsys, monkeypatch, command, name, data, words):
    import rayvr as rv

    folder = tmp_path / "scene"
    folder.mkdir()
    path = folder / "scene.glb"
    path.write_bytes(data)
    graphs = tmp_path / "graphs"
    rv.graphs.hybrid(preset="raw").save(graphs / "g.json")
    argv = (["tune", str(path), "--quiet", "--size", "8x8", "--report", str(tmp_path / "out" / "report"),
             "--cache", str(tmp_path / "out" / "cache")] if command == "tune"
            else ["graph", "show", str(graphs / "g.json"), "--scene", str(path),
                  "--png", str(tmp_path / "out" / "g.png")])
    _expect_refusal(argv, path, words, capsys, monkeypatch, tmp_path, extra_allowed=[graphs])


@pytest.mark.parametrize("name, mutate, words", GLTF_CASES, ids=[c[0] for c in GLTF_CASES])
def test_malformed_gltf_through_render(tmp_path, capsys, monkeypatch, name, mutate, words):
    path = _build(tmp_path, mutate)
    _expect_refusal(_render_argv(path, tmp_path), path, words, capsys, monkeypatch, tmp_path)


def test_the_corpus_is_big_enough():
    assert len(GLB_CASES) + len(GLTF_CASES) >= 40


@pytest.mark.parametrize("case", ["huge count in a bufferView", "huge count without bufferView",
                                  "huge buffer byteLength"])
def test_huge_declared_sizes_are_refused_before_allocation(tmp_path, case):
    import rayvr as rv

    mutate = dict((c[0], c[1]) for c in GLTF_CASES)[case]
    path = _build(tmp_path, mutate)
    tracemalloc.start()
    with pytest.raises(rv.SceneError):
        rv.load_scene(path)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 16 << 20, peak   # the declared sizes are terabytes


@pytest.mark.parametrize("path", [None, 3, ["scene.glb"]])
def test_load_scene_of_something_not_a_path_is_a_scene_error(path):
    import rayvr as rv

    with pytest.raises(rv.SceneError, match="expected the path of a .gltf or .glb file"):
        rv.load_scene(path)


def test_a_valid_glb_and_gltf_of_the_corpus_load(tmp_path):
    """The corpus mutates files that load: so each refusal is the mutation's."""
    import rayvr as rv

    (tmp_path / "ok.glb").write_bytes(valid_glb())
    assert rv.load_scene(tmp_path / "ok.glb").triangle_count == 2
    assert rv.load_scene(_build(tmp_path, lambda doc, folder: None)).triangle_count == 2


def test_sparse_accessors_are_applied(tmp_path):
    import rayvr as rv

    path = _build(tmp_path, _sparse([1, 3]))
    positions = rv.load_scene(path).meshes[0].positions
    expected = QUAD_P.copy()
    expected[[1, 3]] = 0.0
    np.testing.assert_array_equal(positions, expected)


def test_warnings_print_once_one_line_each_and_do_not_fail(tmp_path, capsys):
    def mutate(doc, folder):
        doc["asset"]["version"] = "2.1"
        doc["extensionsUsed"] = ["KHR_materials_sheen"]
        doc["materials"].append({"name": "Red"})
        doc["materials"][0]["extensions"] = {"KHR_materials_sheen": {"sheenRoughnessFactor": 0.5}}

    path = _build(tmp_path, mutate)
    code = main(["render", str(path), "--views", "1", "--size", "8x8", "--out", str(tmp_path / "out" / "x.png")])
    err = capsys.readouterr().err
    assert code == 0, err
    lines = err.strip().splitlines()
    assert len(lines) == 4 and all(line.startswith("rayvr: warning: ") and "scene.gltf" in line for line in lines)
    assert any("no light" in line and "neutral uniform environment" in line for line in lines)
    assert any("asset.version" in line for line in lines)
    assert any("KHR_materials_sheen" in line and "not implemented" in line for line in lines)
    assert any("materials: names repeat ('Red' x2)" in line for line in lines)
    # library users get the same lines through the warnings module
    import rayvr as rv

    with pytest.warns(rv.SceneWarning) as record:
        scene = rv.load_scene(path)
    assert [str(w.message) for w in record] == scene.warnings and record[0].filename == __file__
    assert len(scene.warnings) == 3 and [m.name for m in scene.materials] == ["Red", "Red.1"]


def test_a_required_extension_that_is_implemented_loads(tmp_path):
    import rayvr as rv

    path = _build(tmp_path, _merge({"extensionsUsed": ["KHR_materials_ior"],
                                    "extensionsRequired": ["KHR_materials_ior"]}))
    assert rv.load_scene(path).warnings == []


def test_nan_text_is_not_json_even_inside_extras(tmp_path):
    import rayvr as rv

    path = _build(tmp_path, _raw(b'{"asset": {"version": "2.0"}, "extras": {"x": Infinity}}'))
    with pytest.raises(rv.SceneError, match="Infinity is not a JSON number"):
        rv.load_scene(path)
