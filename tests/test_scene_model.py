"""The CPU scene model and the built-in scenes."""
import numpy as np
import pytest

import rayvr as rv
from rayvr.errors import OptionError, SceneError
from rayvr.scene import Material, Mesh, Scene
from rayvr.scene import builtin
from rayvr.scene.model import vertex_normals


def test_cornell_box_has_the_classic_layout():
    s = builtin.cornell_box()
    assert {"Floor", "Ceiling", "BackWall", "LeftWall", "RightWall", "ShortBox", "TallBox", "Light"} <= set(s.materials.names())
    lo, hi = s.bounds()
    np.testing.assert_allclose(hi - lo, [0.556, 0.5488, 0.5592], atol=2e-3)
    assert s.materials["LeftWall"].base_color[0] > 0.5 > s.materials["LeftWall"].base_color[1]   # red
    assert s.materials["RightWall"].base_color[1] > s.materials["RightWall"].base_color[0]        # green
    light = s.materials["Light"]
    np.testing.assert_allclose(light.emission, [17, 12, 4], rtol=1e-6)
    assert s.features == {"SCENE_HAS_EMISSIVE_TRIANGLES"}
    cam = s.cameras[0]
    # the red wall is on the camera's left: camera right is +x, red wall at -x
    red = s.meshes[[i.name for i in s.instances].index("LeftWall")].positions
    assert red[:, 0].max() < 0 and cam.transform[0, 0] > 0.99
    assert s.triangle_count < 100


def test_walls_face_into_the_box():
    s = builtin.cornell_box()
    centre = s.bounds().mean(axis=0)
    for inst in s.instances:
        m = s.meshes[inst.mesh]
        if inst.name in ("ShortBox", "TallBox", "Light"):
            continue
        t = m.triangles().astype(float)
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        assert (np.einsum("ij,ij->i", n, centre - t[:, 0]) > 0).all(), inst.name


def test_material_edits_bump_the_version_and_parse_effects():
    s = builtin.mirror_and_checker()
    v = s.materials.version
    s.materials["CheckerWhite"].effect = "reflections"
    assert s.materials["CheckerWhite"].effect is rv.Effect.REFLECTIONS
    assert s.materials.version > v
    assert rv.Effect.REFLECTIONS in s.effects_used()
    with pytest.raises(OptionError, match="CheckerWhite.*unknown effect"):
        s.materials["CheckerWhite"].effect = "mirror"
    with pytest.raises(SceneError, match="no material named 'Miror'.*did you mean 'Mirror'"):
        s.materials["Miror"]


def test_duplicate_material_names_get_suffixes():
    s = Scene()
    s.add_material(Material("A"))
    s.add_material(Material("A"))
    assert s.materials.names() == ["A", "A.1"]


def test_bad_meshes_are_refused_with_the_field():
    with pytest.raises(SceneError, match="'bad'.positions: NaN"):
        Mesh("bad", [[0, 0, 0], [1, np.nan, 0], [0, 1, 0]], [[0, 1, 2]], 0)
    with pytest.raises(SceneError, match="'bad'.indices: index 5 out of range"):
        Mesh("bad", np.zeros((3, 3)), [[0, 1, 5]], 0)
    s = Scene()
    s.add_material(Material("M"))
    with pytest.raises(SceneError, match="material_ids.*material 3 does not exist"):
        s.add_mesh(Mesh("m", np.eye(3), [[0, 1, 2]], 3))
    with pytest.raises(SceneError, match="instance 'x'.mesh: index 2 out of range"):
        s.add_instance(2, name="x")


def test_degenerate_triangles_give_finite_normals():
    p = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 0, 1], [5, 5, 5]], np.float32)
    n = vertex_normals(p, np.array([[0, 1, 2], [0, 3, 1], [4, 4, 4]], np.uint32))
    assert np.isfinite(n).all()
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1, rtol=1e-5)
    np.testing.assert_allclose(n[3], [0, 1, 0], atol=1e-6)


def test_features_follow_the_content():
    s = builtin.spheres()
    assert "SCENE_HAS_PUNCTUAL_LIGHTS" in s.features and "SCENE_HAS_TRANSMISSION" not in s.features
    s.materials["Sphere_0_0"].transmission = 1.0
    assert "SCENE_HAS_TRANSMISSION" in s.features
    assert "SCENE_HAS_INSTANCING" in builtin.instanced_boxes().features
    s.materials["Sphere_0_1"].alpha_mode = "mask"
    assert "SCENE_HAS_ALPHA_MASK" in s.features


def test_bounds_follow_instance_transforms():
    s = builtin.instanced_boxes(2)
    lo, hi = s.bounds()
    # box 0: half size 0.25 at (3, 0, 0); box 1: rotated 180 deg, half size 0.375 at (-3, 0.5, 0)
    np.testing.assert_allclose(lo, [-3.375, -0.25, -0.375], atol=1e-9)
    np.testing.assert_allclose(hi, [3.25, 0.875, 0.375], atol=1e-9)


def test_test_scenes_have_what_their_docstrings_promise():
    p = builtin.plane_with_point_light(height=2.0, intensity=3.0)
    assert p.lights[0].intensity == 3.0 and p.lights[0].position[1] == 2.0
    b = builtin.box_on_plane()
    assert len(b.instances) == 2 and b.triangle_count == 14
    m = builtin.mirror_and_checker(tiles=4)
    mesh = m.meshes[m.instances[1].mesh]
    assert sorted(np.unique(mesh.material_ids).tolist()) == [1, 2] and mesh.triangle_count == 32
    assert m.materials["Mirror"].effect is rv.Effect.REFLECTIONS
    q = builtin.quad()
    assert q.triangle_count == 2 and q.meshes[0].uvs is not None


def test_rv_scenes_alias_is_the_builtin_module():
    assert rv.scenes.cornell_box().name == "cornell_box"


@pytest.mark.parametrize("slot", ["metallic_roughness_texture", "occlusion_texture", "emissive_texture",
                                  "transmission_texture", "base_color_texture", "normal_texture"])
def test_setting_any_texture_slot_bumps_the_version(slot):
    """GpuScene re-uploads materials on a version change; every texture slot is in the upload."""
    s = builtin.quad()
    v = s.materials.version
    setattr(s.materials["Quad"], slot, rv.scene.TextureRef(0))
    assert s.materials.version > v


def test_emission_through_a_texture_does_not_count_as_lighting_the_scene():
    """A lamp (emission without a texture) lights its scene; a helmet's glowing details or a label
    (emission through an emissive texture) do not, so such a scene gets the neutral environment
    instead of rendering nearly black."""
    from rayvr.scene import DEFAULT_ENVIRONMENT
    from rayvr.scene.model import Texture

    for textured, lit in ((False, True), (True, False)):
        s = builtin.quad()
        s.textures.append(Texture(np.full((2, 2, 4), 255, np.uint8)))
        m = s.materials["Quad"]
        m.emissive = (1.0, 1.0, 1.0)
        if textured:
            m.emissive_texture = rv.scene.TextureRef(0)
        assert s.has_light() == lit
        assert (s.lighting_environment() is DEFAULT_ENVIRONMENT) == (not lit)
