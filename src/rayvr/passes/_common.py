"""Helpers the hybrid passes share: shader paths, scene defines, texture binding."""
from __future__ import annotations

from pathlib import Path

from ..errors import GraphError
from ..gpu.shaders import compute_program
from ..materials.effect import Effect
from ..rendergraph.registry import register_pass as register  # noqa: F401  (the passes' class decorator)

SHADER_DIR = Path(__file__).resolve().parent / "shaders"

# Sampler units of the G-buffer inputs (glsl/gbuffer.glsl reads them from these #defines).
GBUFFER_UNITS = {"GBUF_POS_UNIT": 0, "GBUF_NORMAL_UNIT": 1, "GBUF_FACE_NORMAL_UNIT": 2,
                 "GBUF_BASE_COLOR_UNIT": 3, "GBUF_METAL_ROUGH_UNIT": 4, "GBUF_EFFECT_UNIT": 5,
                 "GBUF_EMISSIVE_UNIT": 6}
# The G-buffer pins in the order of their units above.
GBUFFER_PINS = ("posW", "normW", "faceNormalW", "baseColor", "metalRough", "effect", "emissive")

COMPUTE_GROUP = (8, 8)   # the local size of the passes' 2D compute shaders


def scene_defines(ctx) -> dict:
    """The GpuScene's feature #defines (none without a scene)."""
    return {} if ctx.scene is None else dict(ctx.scene.defines())


def build_compute(gl, name: str, defines: dict | None = None):
    """A compute program from passes/shaders/NAME (cached per source and defines)."""
    return compute_program(gl, SHADER_DIR / name, defines)


# Views a ray pass's warp spans (glsl/ray_group.glsl). Neighbouring views of a camera grid see
# nearly the same surface through the same pixel (exactly so on the focal plane), so a warp of a
# few pixels in several views traces more alike rays than one of more pixels in one small view.
# Each pass may pass its own count to ray_group; 1: off. Measured on the H100, tauray, 64 views of
# 512x683, GPU ms for groups of 1 / 2 / 4 / 8 views: GBufferRT 2.87 / 2.71 / 3.04 / 3.83, RTShadows
# 7.47 / 7.38 / 7.26 / 7.24 (primary rays only diverge so far before a wider warp costs more).
VIEW_GROUP = 4
# Frames with fewer views are not grouped: stereo's two eyes see the same pixel's surface far apart.
MIN_GROUPED_VIEWS = 4


def groups_2d(size: tuple[int, int], views: int, group: tuple[int, ...] = COMPUTE_GROUP) -> tuple[int, int, int]:
    """Workgroups covering `size` pixels of every view with `group`-sized workgroups: (x, y) pixels,
    or (x, y, z) pixels by views."""
    gx, gy, gz = (*group, 1)[:3]
    return (size[0] + gx - 1) // gx, (size[1] + gy - 1) // gy, (views + gz - 1) // gz


def ray_group(views: int, tile: tuple[int, int] = COMPUTE_GROUP, view_group: int | None = None) -> tuple[int, int, int]:
    """The (x, y, views) shape of a ray pass's workgroup of tile[0] * tile[1] invocations: the tile
    shrunk (larger side first) to make room for `view_group` views (default VIEW_GROUP) when a frame
    has at least MIN_GROUPED_VIEWS."""
    x, y = tile
    z = 1
    want = VIEW_GROUP if view_group is None else view_group
    while z < want and views >= max(want, MIN_GROUPED_VIEWS) and x * y > 1:
        z *= 2
        if x > y:
            x //= 2
        else:
            y //= 2
    return x, y, z


def ray_group_defines(group: tuple[int, int, int]) -> dict:
    """The #defines glsl/ray_group.glsl reads."""
    return {"RAY_GROUP_X": group[0], "RAY_GROUP_Y": group[1], "RAY_GROUP_Z": group[2]}


def bind_scene(ctx) -> None:
    """Bind the views SSBO and the GpuScene's buffers and textures."""
    from ..gpu.bindings import BINDINGS

    if ctx.views_buffer is not None:
        ctx.views_buffer.bind_to_storage_buffer(BINDINGS["RAYVR_VIEWS_SSBO"])
    if ctx.scene is not None:
        ctx.scene.bind()


def require_scene(ctx, render_pass) -> None:
    """GraphError naming the pass when the graph was compiled without a scene."""
    if ctx.scene is None:
        raise GraphError(f"pass {render_pass.name} ({type(render_pass).__name__}) needs a scene: compile the "
                         f"graph with a scene (rv.Renderer(scene, graph) does)")




def effect_defines() -> dict:
    """EFFECT_RASTER .. EFFECT_PATH_TRACED as #defines, so GLSL and rayvr.Effect agree."""
    return {f"EFFECT_{e.name}": int(e) for e in Effect}


def effects_used(cd) -> set | None:
    """The effects the scene's materials use, or None without a scene (then nothing is skipped)."""
    return None if cd.scene is None else set(cd.scene.effects_used())


def unused_effect_reason(cd, lowest: Effect) -> str | None:
    """The skip reason of a pass that serves effect `lowest` and above, when no material uses one
    of them (None without a scene, or when one is used)."""
    used = effects_used(cd)
    if used is None or any(e >= lowest for e in used):
        return None
    return f"no material uses {lowest.name}" + ("" if lowest == max(Effect) else " or above")
