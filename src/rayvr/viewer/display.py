"""Draw the graph's output texture array into the window: the views side by side, or one eye,
fitted to the window with their aspect kept. One draw for all views: the fragment shader picks
the layer from its position. Pixels are taken as they are (nearest texel): the output is rgba8
sRGB-encoded (ToneMap.dst) and the window's framebuffer is not an sRGB one, so nothing converts.
An optional overlay array of the same layout (`error_overlay`, e.g. an error map) is blended on top."""
from __future__ import annotations

import moderngl

MODES = ("side_by_side", "left", "right")
BACKGROUND = (0.08, 0.08, 0.09)

_VERTEX = """
#version 450
out vec2 uv;
void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
    uv = p;
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
"""

_FRAGMENT = """
#version 450
in vec2 uv;
out vec4 color;
layout(binding = 0) uniform sampler2DArray frame;
layout(binding = 1) uniform sampler2DArray overlay;
uniform int first_layer;
uniform int layer_count;
uniform float overlay_alpha;
void main() {
    float x = uv.x * float(layer_count);
    int k = min(int(x), layer_count - 1);
    vec3 st = vec3(x - float(k), uv.y, float(first_layer + k));
    vec4 c = texture(frame, st);
    if (overlay_alpha > 0.0) {
        vec4 o = texture(overlay, st);
        c.rgb = mix(c.rgb, o.rgb, overlay_alpha * o.a);
    }
    color = vec4(c.rgb, 1.0);
}
"""


def fit(image_size, target_size) -> tuple[int, int, int, int]:
    """The viewport (x, y, w, h) that shows `image_size` as large as fits in `target_size`,
    centred, its aspect kept; exactly the target when the sizes match."""
    iw, ih = image_size
    tw, th = target_size
    scale = min(tw / iw, th / ih)
    w, h = max(1, round(iw * scale)), max(1, round(ih * scale))
    return (tw - w) // 2, (th - h) // 2, w, h


class FrameDisplay:
    """The program and sampler that put a texture array on the screen."""

    def __init__(self, gl: moderngl.Context):
        self.gl = gl
        self.program = gl.program(vertex_shader=_VERTEX, fragment_shader=_FRAGMENT)
        self.vao = gl.vertex_array(self.program, [])
        # A sampler object, never texture state: the graph's textures may be shared (CONTRACTS).
        self.sampler = gl.sampler(filter=(moderngl.NEAREST, moderngl.NEAREST), repeat_x=False, repeat_y=False)

    def layout(self, views: int, mode: str) -> tuple[int, int]:
        """(first layer, layer count) that `mode` shows of `views` layers."""
        if mode not in MODES:
            from ..errors import OptionError

            raise OptionError(f"display mode '{mode}': use one of {', '.join(MODES)}")
        if mode == "side_by_side" or views == 1:
            return 0, views
        return (0 if mode == "left" else views - 1), 1

    def draw(self, framebuffer, target_size, frame, views: int, view_size, mode: str = "side_by_side",
             overlay=None, overlay_alpha: float = 0.0) -> tuple[int, int, int, int]:
        """Clear `framebuffer` and draw `frame` (a texture array of `views` layers of `view_size`)
        in `mode`; returns the viewport the image took (x, y from the bottom-left, w, h)."""
        first, count = self.layout(views, mode)
        rect = fit((view_size[0] * count, view_size[1]), target_size)
        framebuffer.use()
        framebuffer.viewport = (0, 0, *target_size)
        framebuffer.clear(*BACKGROUND, 1.0)
        framebuffer.viewport = rect
        self.gl.disable(moderngl.BLEND | moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        self.program["first_layer"] = first
        self.program["layer_count"] = count
        self.program["overlay_alpha"] = float(overlay_alpha if overlay is not None else 0.0)
        frame.use(location=0)
        self.sampler.use(location=0)
        if overlay is not None:
            overlay.use(location=1)
            self.sampler.use(location=1)
        self.vao.render(moderngl.TRIANGLES, vertices=3)
        self.sampler.clear(location=0)
        if overlay is not None:
            self.sampler.clear(location=1)
        framebuffer.viewport = (0, 0, *target_size)
        return rect

    def release(self) -> None:
        self.sampler.release()
        self.vao.release()
        self.program.release()
