"""Binding a pass's textures, images and buffers to a program by their GLSL names.

Passes never pick sampler units, image units or SSBO binding points by hand: the first time a
program is bound, its reflection (moderngl's members) gives every sampler uniform a texture unit,
every image uniform an image unit and every storage block a binding point, in name order, and
sets them on the program once. The frame-wide resources keep their fixed points
(`bindings.SHARED_BLOCKS`: the views and the GPU scene; the scene's texture unit; the ray
counters' image unit, the last), which the allocation skips.

    res = program_resources(prog)
    res.texture("gbuf_posW", data["posW"])
    res.image("dst", data["color"], write=True)
    res.buffer("PixelList", data["pixels"])

A name the GLSL compiler removed (unused) binds nothing.
"""
from __future__ import annotations

import ctypes

from ..errors import ShaderError
from .bindings import FIRST_PASS_SSBO, SCENE_TEXTURE_UNITS, SHARED_BLOCKS, SHARED_IMAGES, SHARED_SAMPLERS

# GL type enums of sampler and image uniforms (glGetActiveUniform), the ones rayvr's GLSL uses.
_SAMPLER_TYPES = {
    0x8B5E, 0x8B5F, 0x8B60, 0x8DC0, 0x8DC1,            # sampler2D, 3D, Cube, 1DArray, 2DArray
    0x8DCA, 0x8DCB, 0x8DCC, 0x8DCF,                    # isampler2D, 3D, Cube, 2DArray
    0x8DD2, 0x8DD3, 0x8DD4, 0x8DD7,                    # usampler2D, 3D, Cube, 2DArray
    0x8B62, 0x8DC4, 0x8DC5,                            # sampler2DShadow, 2DArrayShadow, CubeShadow
}
_IMAGE_TYPES = {
    0x904D, 0x904E, 0x9050, 0x9053,                    # image2D, 3D, Cube, 2DArray
    0x9058, 0x9059, 0x905E,                            # iimage2D, 3D, 2DArray
    0x9063, 0x9064, 0x9069,                            # uimage2D, 3D, 2DArray
}
MAX_PASS_TEXTURE_UNITS = 16
MAX_PASS_IMAGE_UNITS = 8
MAX_PASS_SSBOS = 16


class ProgramResources:
    """The texture units, image units and SSBO points of one program's own resources."""

    def __init__(self, prog):
        import moderngl

        self.prog = prog
        self.units: dict[str, int] = {}
        self.image_units: dict[str, int] = {}
        self.ssbos: dict[str, int] = {}
        samplers, images, blocks = [], [], []
        for name in prog:
            member = prog[name]
            if isinstance(member, moderngl.StorageBlock):
                if name not in SHARED_BLOCKS:
                    blocks.append(name)
            elif isinstance(member, moderngl.Uniform):
                if member.gl_type in _SAMPLER_TYPES and name not in SHARED_SAMPLERS:
                    samplers.append(name)
                elif member.gl_type in _IMAGE_TYPES and name not in SHARED_IMAGES:
                    images.append(name)
        shared_images = sum(1 for name in SHARED_IMAGES if name in prog)
        reserved = set(SCENE_TEXTURE_UNITS)
        free_units = [u for u in range(MAX_PASS_TEXTURE_UNITS + len(reserved)) if u not in reserved]
        where = getattr(prog, "rayvr_name", "program")
        for kind, names, limit in (("sampler", samplers, len(free_units)),
                                   ("image", images, MAX_PASS_IMAGE_UNITS - shared_images),
                                   ("storage block", blocks, MAX_PASS_SSBOS)):
            if len(names) > limit:
                raise ShaderError(f"{where}: {len(names)} {kind} resources, more than the {limit} a pass may bind; "
                                  f"split the pass")
        for unit, name in zip(free_units, sorted(samplers)):
            prog[name].value = unit
            self.units[name] = unit
        for unit, name in enumerate(sorted(images)):
            _set_int_uniform(prog, prog[name].location, unit)
            self.image_units[name] = unit
        for point, name in enumerate(sorted(blocks), start=FIRST_PASS_SSBO):
            prog[name].binding = point
            self.ssbos[name] = point

    def texture(self, name: str, texture, sampler=None) -> None:
        """Sample `texture` through the sampler uniform `name` (with `sampler`'s filtering if given)."""
        unit = self.units.get(name)
        if unit is None:
            return
        texture.use(location=unit)
        if sampler is not None:
            sampler.use(location=unit)

    def clear_sampler(self, name: str) -> None:
        """Unbind the sampler object from `name`'s unit (textures filter by their own state again)."""
        unit = self.units.get(name)
        if unit is not None:
            self.prog.ctx.clear_samplers(unit, unit + 1)

    def image(self, name: str, texture, read: bool = False, write: bool = True, level: int = 0) -> None:
        """Bind `texture` (all layers) to the image uniform `name` for loads and/or stores."""
        unit = self.image_units.get(name)
        if unit is not None:
            texture.bind_to_image(unit, read=read, write=write, level=level)

    def buffer(self, name: str, buffer) -> None:
        """Bind `buffer` to the storage block `name`."""
        point = self.ssbos.get(name)
        if point is not None:
            buffer.bind_to_storage_buffer(point)

    def set(self, name: str, value) -> None:
        """Set the plain uniform `name` (skipped when the compiler removed it)."""
        if name in self.prog:
            self.prog[name].value = value


_cache: dict[int, ProgramResources] = {}


def program_resources(prog) -> ProgramResources:
    """The (cached) ProgramResources of `prog`: programs are shared between passes with the same
    source and defines, and so are their unit assignments."""
    res = _cache.get(id(prog))
    if res is None or res.prog is not prog:
        res = _cache[id(prog)] = ProgramResources(prog)
    return res


def _set_int_uniform(prog, location: int, value: int) -> None:
    """glProgramUniform1i: moderngl does not set image uniforms."""
    from .rawgl import ProcLoader

    global _program_uniform
    if _program_uniform is None:
        _program_uniform = ProcLoader().proc("glProgramUniform1i", None,
                                             [ctypes.c_uint, ctypes.c_int, ctypes.c_int])
    _program_uniform(prog.glo, location, value)


_program_uniform = None
