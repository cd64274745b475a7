import numpy as np
import pytest

from rayvr.errors import ShaderError
from rayvr.gpu import compute_program, preprocess
from rayvr.gpu.bindings import BINDINGS


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_include_and_defines_reach_the_program(gl, tmp_path):
    write(tmp_path, "lib.glsl", "#pragma once\nfloat scale() { return float(SCALE); }\n")
    main = write(tmp_path, "main.comp", """
#include "lib.glsl"
#include "lib.glsl"
layout(local_size_x = 4) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) buffer Out { float v[]; };
void main() { v[gl_GlobalInvocationID.x] = scale() * float(gl_GlobalInvocationID.x); }
""")
    prog = compute_program(gl, main, {"SCALE": 3})
    buf = gl.buffer(reserve=16)
    buf.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"])
    prog.run(1)
    np.testing.assert_array_equal(np.frombuffer(buf.read(), "f4"), [0, 3, 6, 9])


def test_include_under_a_false_if_leaves_the_file_to_a_later_include(gl, tmp_path):
    write(tmp_path, "lib.glsl", "#pragma once\nfloat scale() { return 5.0; }\n")
    write(tmp_path, "optional.glsl", "#pragma once\n#if USE_LIB\n#include \"lib.glsl\"\n#endif\n")
    main = write(tmp_path, "main.comp", """
#include "optional.glsl"
#include "lib.glsl"
layout(local_size_x = 2) in;
layout(std430, binding = RAYVR_PASS_SSBO_0) buffer Out { float v[]; };
void main() { v[gl_GlobalInvocationID.x] = scale(); }
""")
    prog = compute_program(gl, main, {"USE_LIB": 0})
    buf = gl.buffer(reserve=8)
    buf.bind_to_storage_buffer(BINDINGS["RAYVR_PASS_SSBO_0"])
    prog.run(1)
    np.testing.assert_array_equal(np.frombuffer(buf.read(), "f4"), [5, 5])


def test_compile_error_names_the_included_file_and_line(gl, tmp_path):
    write(tmp_path, "bad.glsl", "float ok() { return 1.0; }\nfloat broken() { return undefined_name; }\n")
    main = write(tmp_path, "entry.comp", '#include "bad.glsl"\nlayout(local_size_x=1) in;\nvoid main() {}\n')
    with pytest.raises(ShaderError) as err:
        compute_program(gl, main)
    assert f"{tmp_path / 'bad.glsl'}:2" in str(err.value)


def test_missing_include_names_the_file(tmp_path):
    main = write(tmp_path, "m.comp", '#include "nowhere.glsl"\n')
    with pytest.raises(ShaderError, match=r"nowhere\.glsl.*not found"):
        preprocess(main)


def test_circular_include_is_refused(tmp_path):
    write(tmp_path, "a.glsl", '#include "b.glsl"\n')
    write(tmp_path, "b.glsl", '#include "a.glsl"\n')
    with pytest.raises(ShaderError, match="circular"):
        preprocess(tmp_path / "a.glsl")


def test_shared_glsl_is_found_without_a_path(tmp_path):
    main = write(tmp_path, "v.comp", '#include "views.glsl"\nlayout(local_size_x=1) in;\nvoid main() {}\n')
    src = preprocess(main)
    assert any(f.name == "views.glsl" for f in src.files)
    assert "#define RAYVR_VIEWS_SSBO 0" in src.text


def test_include_with_a_trailing_comment_is_expanded(tmp_path):
    write(tmp_path, "lib.glsl", "float from_lib() { return 2.0; }\n")
    main = write(tmp_path, "m.comp", '#include "lib.glsl"   // the library\nlayout(local_size_x=1) in;\nvoid main() {}\n')
    src = preprocess(main)
    assert "from_lib" in src.text and "#include" not in src.text
