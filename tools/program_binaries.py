#!/usr/bin/env python3
"""Run a benchmark with every compute program's driver binary saved (a device-machine tool).

    OUT=DIR python3 tools/program_binaries.py rays --scenes .scenes/tauray_test.glb --size 256x256 --bvh-layouts bvh4,bvh8

runs `python3 -m benchmarks ARGS` with `moderngl.Context.compute_shader` wrapped: each program's
`glGetProgramBinary` goes to DIR/bin/HASH.bin beside its source, HASH.glsl (HASH: the source's
SHA-1, 10 digits). NVIDIA's binaries keep the driver's intermediate assembly (`!!NVcp5.0`) as text,
so `strings HASH.bin` shows each kernel's instructions, temporaries and local-memory arrays; tar
DIR/bin before it comes back (a device call returns only so many files).
"""
import ctypes
import hashlib
import os
import runpy
import sys

import moderngl

GL_PROGRAM_BINARY_LENGTH = 0x8741


def main() -> None:
    out = os.path.join(os.environ.get("OUT", "/tmp/out"), "bin")
    os.makedirs(out, exist_ok=True)
    gl = ctypes.CDLL("libOpenGL.so.0")
    get_iv, get_binary = gl.glGetProgramiv, gl.glGetProgramBinary
    get_iv.argtypes = [ctypes.c_uint, ctypes.c_uint, ctypes.POINTER(ctypes.c_int)]
    get_binary.argtypes = [ctypes.c_uint, ctypes.c_int, ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_uint),
                           ctypes.c_void_p]
    compile_compute = moderngl.Context.compute_shader

    def saving(self, source, *args, **kwargs):
        prog = compile_compute(self, source, *args, **kwargs)
        size, length, fmt = ctypes.c_int(0), ctypes.c_int(0), ctypes.c_uint(0)
        get_iv(prog.glo, GL_PROGRAM_BINARY_LENGTH, ctypes.byref(size))
        data = ctypes.create_string_buffer(max(size.value, 1))
        get_binary(prog.glo, size.value, ctypes.byref(length), ctypes.byref(fmt), data)
        name = hashlib.sha1(source.encode()).hexdigest()[:10]
        with open(os.path.join(out, f"{name}.bin"), "wb") as f:
            f.write(data.raw[:length.value])
        with open(os.path.join(out, f"{name}.glsl"), "w") as f:
            f.write(source)
        print(f"program_binaries: {name} {length.value} bytes, format {fmt.value:#x}", file=sys.stderr)
        return prog

    moderngl.Context.compute_shader = saving
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    sys.argv = ["benchmarks", *sys.argv[1:]]
    runpy.run_module("benchmarks", run_name="__main__", alter_sys=True)


if __name__ == "__main__":
    main()
