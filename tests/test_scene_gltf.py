"""glTF 2.0 loading: tiny files built in code; counts, transforms, materials, extensions, bad input."""
import base64
import io
import json
import math
import pathlib

import numpy as np
import pytest
from PIL import Image

import rayvr as rv
from rayvr.errors import SceneError
from rayvr.materials import AlphaMode

QUAD_P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32)
QUAD_UV = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], np.float32)
QUAD_I = np.array([0, 1, 2, 0, 2, 3], np.uint32)


def png_data_uri(rgba) -> str:
    buf = io.BytesIO()
    Image.fromarray(np.asarray(rgba, np.uint8)).save(buf, format="PNG")
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()


def base_doc(positions=QUAD_P, indices=QUAD_I, uvs=QUAD_UV, bin_name="data.bin"):
    blobs = [positions.astype(np.float32).tobytes(), indices.astype(np.uint32).tobytes(), uvs.astype(np.float32).tobytes()]
    offsets = np.cumsum([0] + [len(b) for b in blobs])
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"uri": bin_name, "byteLength": int(offsets[-1])}],
        "bufferViews": [{"buffer": 0, "byteOffset": int(offsets[k]), "byteLength": len(blobs[k])} for k in range(3)],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(positions), "type": "VEC3",
             # bounds of the finite values: NaN test data stays in the binary, JSON has no NaN
             "min": np.nanmin(np.where(np.isfinite(positions), positions, np.nan), 0).tolist(),
             "max": np.nanmax(np.where(np.isfinite(positions), positions, np.nan), 0).tolist()},
            {"bufferView": 1, "componentType": 5125, "count": len(indices), "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": len(uvs), "type": "VEC2"},
        ],
        "materials": [{"name": "Red", "pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1], "metallicFactor": 0.0}}],
        "meshes": [{"name": "Quad", "primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 2}, "indices": 1, "material": 0}]}],
        "nodes": [{"name": "Q", "mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    return doc, b"".join(blobs)


def write(tmp_path, doc, blob, name="scene.gltf"):
    folder = tmp_path / "scene"
    folder.mkdir(exist_ok=True)
    (folder / doc["buffers"][0]["uri"]).write_bytes(blob)
    p = folder / name
    p.write_text(json.dumps(doc))
    return p


def test_hierarchy_instancing_and_transforms(tmp_path):
    doc, blob = base_doc()
    doc["nodes"] = [
        {"name": "Parent", "translation": [10, 0, 0], "scale": [2, 2, 2], "children": [1, 2]},
        {"name": "A", "mesh": 0},
        {"name": "B", "mesh": 0, "rotation": [0, math.sin(math.pi / 4), 0, math.cos(math.pi / 4)], "translation": [0, 1, 0]},
        {"name": "M", "mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 5, 6, 7, 1]},
    ]
    doc["scenes"] = [{"nodes": [0, 3]}]
    s = rv.load_scene(write(tmp_path, doc, blob))
    assert len(s.meshes) == 1 and len(s.instances) == 3 and s.triangle_count == 6
    assert "SCENE_HAS_INSTANCING" in s.features
    by = {i.name: i.transform for i in s.instances}
    np.testing.assert_allclose(by["A"][:3, 3], [10, 0, 0])
    np.testing.assert_allclose(by["A"][:3, :3], 2 * np.eye(3))
    np.testing.assert_allclose(by["B"][:3, 3], [10, 2, 0])
    np.testing.assert_allclose(by["B"][:3, :3] @ [1, 0, 0], [0, 0, -2], atol=1e-12)   # +90 deg about +Y
    np.testing.assert_allclose(by["M"][:3, 3], [5, 6, 7])
    np.testing.assert_array_equal(s.meshes[0].indices, QUAD_I.reshape(-1, 3))
    np.testing.assert_allclose(s.meshes[0].uvs, QUAD_UV)
    np.testing.assert_allclose(s.meshes[0].normals, [[0, 0, 1]] * 4, atol=1e-6)


def test_materials_extensions_lights_cameras_and_effect(tmp_path):
    doc, blob = base_doc()
    tex = np.zeros((2, 2, 4), np.uint8)
    tex[..., 3] = 255
    tex[0, 0, :3] = 255
    doc["images"] = [{"uri": png_data_uri(tex)}]
    doc["textures"] = [{"source": 0}]
    doc["extensionsUsed"] = ["KHR_materials_emissive_strength", "KHR_materials_transmission",
                             "KHR_materials_ior", "KHR_texture_transform", "KHR_lights_punctual"]
    doc["materials"] = [{
        "name": "Glass",
        "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.6, 0.7, 0.8], "metallicFactor": 0.25, "roughnessFactor": 0.125,
                                 "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": {
                                     "offset": [0.5, 0.25], "rotation": 0.5, "scale": [2, 3]}}}},
        "emissiveFactor": [1, 0.5, 0.25],
        "normalTexture": {"index": 0, "scale": 0.75},
        "alphaMode": "MASK", "alphaCutoff": 0.3, "doubleSided": True,
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0},
                       "KHR_materials_transmission": {"transmissionFactor": 0.9},
                       "KHR_materials_ior": {"ior": 1.33}},
        "extras": {"rayvr_effect": "PATH_TRACED"},
    }]
    doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"type": "spot", "color": [1, 0.5, 0], "intensity": 20, "range": 7,
         "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.4}},
        {"type": "directional", "intensity": 3}]}}
    doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 50, "aspectRatio": 1.5}}]
    doc["nodes"] += [
        {"name": "Spot", "translation": [0, 3, 0], "rotation": [-math.sin(math.pi / 4), 0, 0, math.cos(math.pi / 4)],
         "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "Sun", "extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"name": "Cam", "camera": 0, "translation": [0, 1, 5]},
    ]
    doc["scenes"] = [{"nodes": [0, 1, 2, 3]}]
    s = rv.load_scene(write(tmp_path, doc, blob))
    m = s.materials["Glass"]
    assert m.base_color == (0.5, 0.6, 0.7, 0.8) and (m.metallic, m.roughness) == (0.25, 0.125)
    np.testing.assert_allclose(m.emission, [4, 2, 1])
    assert (m.transmission, m.ior, m.alpha_mode, m.alpha_cutoff, m.double_sided) == (0.9, 1.33, AlphaMode.MASK, 0.3, True)
    assert m.effect is rv.Effect.PATH_TRACED
    ref = m.base_color_texture
    assert (ref.texture, ref.offset, ref.rotation, ref.scale) == (0, (0.5, 0.25), 0.5, (2, 3))
    assert m.normal_texture.strength == 0.75
    assert s.textures[0].image.shape == (2, 2, 4) and s.textures[0].image[0, 0, 0] == 255
    assert s.features >= {"SCENE_HAS_TEXTURES", "SCENE_HAS_NORMAL_MAPS", "SCENE_HAS_ALPHA_MASK",
                          "SCENE_HAS_TRANSMISSION", "SCENE_HAS_EMISSIVE_TRIANGLES", "SCENE_HAS_PUNCTUAL_LIGHTS"}
    spot, sun = s.lights
    assert spot.type == 1 and spot.intensity == 20 and spot.range == 7 and spot.outer_cone_angle == 0.4
    np.testing.assert_allclose(spot.position, [0, 3, 0])
    np.testing.assert_allclose(spot.direction, [0, -1, 0], atol=1e-12)   # rotated -90 deg about X: -Z -> -Y
    np.testing.assert_allclose(sun.direction, [0, 0, -1])
    cam = s.cameras[0]
    assert (cam.yfov, cam.znear, cam.zfar, cam.aspect) == (0.8, 0.1, 50, 1.5)
    np.testing.assert_allclose(cam.position, [0, 1, 5])


@pytest.mark.filterwarnings("ignore:Conversion will leave")
def test_glb_and_triangle_strips_load(tmp_path):
    import pygltflib

    doc, blob = base_doc(indices=np.array([0, 1, 3, 2], np.uint32))
    doc["meshes"][0]["primitives"][0]["mode"] = 5
    p = write(tmp_path, doc, blob)
    g = pygltflib.GLTF2().load(str(p))
    g.convert_buffers(pygltflib.BufferFormat.BINARYBLOB)
    glb = tmp_path / "scene" / "scene.glb"
    g.save_binary(str(glb))
    s = rv.load_scene(glb)
    assert s.triangle_count == 2
    tri = s.meshes[0].triangles().astype(float)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert (n[:, 2] > 0).all()   # strip winding alternation keeps both faces front


def expect_error(tmp_path, doc, blob, *patterns):
    with pytest.raises(SceneError) as err:
        rv.load_scene(write(tmp_path, doc, blob))
    for pat in patterns:
        assert pat in str(err.value), str(err.value)
    assert "scene.gltf" in str(err.value)


def test_missing_file_and_wrong_suffix(tmp_path):
    with pytest.raises(SceneError, match="nothere.gltf: file not found"):
        rv.load_scene(tmp_path / "nothere.gltf")
    (tmp_path / "x.obj").write_text("v 0 0 0")
    with pytest.raises(SceneError, match="not a glTF file"):
        rv.load_scene(tmp_path / "x.obj")


def test_broken_json(tmp_path):
    p = tmp_path / "broken.gltf"
    p.write_text('{"asset": {"version": "2.0"}, "meshes": [')
    with pytest.raises(SceneError, match="broken.gltf: broken glTF JSON"):
        rv.load_scene(p)


def test_accessor_out_of_range(tmp_path):
    doc, blob = base_doc()
    doc["accessors"][0]["count"] = 400
    expect_error(tmp_path, doc, blob, "accessors[0]", "POSITION", "run past the end")
    doc, blob = base_doc()
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 9
    expect_error(tmp_path, doc, blob, "meshes[0].primitives[0].attributes.POSITION", "accessor 9 out of range")


def test_index_out_of_range(tmp_path):
    doc, blob = base_doc(indices=np.array([0, 1, 7], np.uint32))
    expect_error(tmp_path, doc, blob, "meshes[0].primitives[0].indices", "index 7 out of range for 4 vertices")


def test_nan_vertices(tmp_path):
    p = QUAD_P.copy()
    p[2, 1] = np.inf
    doc, blob = base_doc(positions=p)
    expect_error(tmp_path, doc, blob, "meshes[0].primitives[0].attributes.POSITION", "NaN or Inf")


def test_undecodable_texture(tmp_path):
    doc, blob = base_doc()
    doc["images"] = [{"uri": "data:image/png;base64," + base64.b64encode(b"not a png").decode()}]
    doc["textures"] = [{"source": 0}]
    expect_error(tmp_path, doc, blob, "images[0]", "cannot be decoded")


def test_uri_outside_the_scene_folder_is_refused_unread(tmp_path, monkeypatch):
    secret = tmp_path / "secret.bin"
    secret.write_bytes(b"\0" * 1024)
    read = []
    orig = pathlib.Path.read_bytes
    monkeypatch.setattr(pathlib.Path, "read_bytes", lambda self: read.append(self) or orig(self))
    for uri in ("../secret.bin", str(secret), "sub/../../secret.bin"):
        doc, blob = base_doc()
        p = write(tmp_path, doc, blob)
        doc["buffers"][0]["uri"] = uri
        p.write_text(json.dumps(doc))
        with pytest.raises(SceneError, match=r"buffers\[0\].uri: URI .* outside the scene folder"):
            rv.load_scene(p)
    assert secret not in [r.resolve() for r in read]
    doc, blob = base_doc()
    doc["images"] = [{"uri": "../secret.bin"}]
    doc["textures"] = [{"source": 0}]
    expect_error(tmp_path, doc, blob, "images[0].uri", "outside the scene folder")


def test_degenerate_triangles_load(tmp_path):
    p = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], np.float32)
    doc, blob = base_doc(positions=p, indices=np.array([0, 1, 2, 0, 1, 3], np.uint32))
    s = rv.load_scene(write(tmp_path, doc, blob))
    assert s.triangle_count == 2 and np.isfinite(s.meshes[0].normals).all()
