"""`rayvr render`: files per view / side by side / EXR / quilt, the timing table, bad options
(exit 2, one line naming the option) and never a half-written output."""
import numpy as np
import pytest
from PIL import Image

from rayvr.cli.main import main


def run(capsys, *argv):
    code = main(["render", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_stereo_png_per_eye_and_timing_table(gpu, tmp_path, capsys):
    code, out, err = run(capsys, "--views", "2", "--size", "24x16", "--out", str(tmp_path / "c.png"))
    assert code == 0, err
    for eye in ("L", "R"):
        img = np.array(Image.open(tmp_path / f"c_{eye}.png"))
        assert img.shape == (16, 24, 3) and img.max() > 0
    assert "GBuffer" in out and "ToneMap" in out and "mean ms" in out
    assert f"wrote {tmp_path / 'c_L.png'}" in out
    assert not list(tmp_path.glob(".*"))   # no temporary files left


def test_side_by_side_and_effect_option(gpu, tmp_path, capsys):
    code, out, err = run(capsys, "--size", "16x16", "--layout", "side-by-side", "--effect", "Floor=reflections",
                         "--effect", "*=shadows", "--effect", "Floor=reflections", "--report",
                         "--out", str(tmp_path / "sbs.png"))
    assert code == 0, err
    assert np.array(Image.open(tmp_path / "sbs.png")).shape == (16, 32, 3)
    assert "Reflections" in out.split("pruned")[0]   # the reflection pass ran


def test_exr_is_linear_hdr(gpu, tmp_path, capsys):
    OpenEXR = pytest.importorskip("OpenEXR")
    code, out, err = run(capsys, "--views", "1", "--size", "16x12", "--exposure", "0", "--out", str(tmp_path / "hdr.exr"))
    assert code == 0, err
    with OpenEXR.File(str(tmp_path / "hdr.exr")) as f:
        rgb = f.channels()["RGB"].pixels
    assert rgb.shape == (12, 16, 3) and rgb.dtype == np.float32 and np.isfinite(rgb).all() and rgb.max() > 0


def test_set_changes_a_pass_property(gpu, tmp_path, capsys):
    code, out, err = run(capsys, "--size", "8x8", "--preset", "raw", "--frames", "1", "--report",
                         "--set", "Shadows.light_samples=3", "--set", "ToneMap.operator=linear",
                         "--out", str(tmp_path / "s.png"))
    assert code == 0, err
    assert "LIGHT_SAMPLES=3" in out.replace(" ", "") or "'LIGHT_SAMPLES': 3" in out


def test_light_field_grid_and_quilt(gpu, tmp_path, capsys):
    code, out, err = run(capsys, "--views", "4", "--grid", "2x2", "--size", "8x8", "--out", str(tmp_path / "v.png"),
                         "--quilt", str(tmp_path / "q.png"))
    assert code == 0, err
    assert len(list(tmp_path.glob("v_v*.png"))) == 4
    quilts = list(tmp_path.glob("q*.png"))
    assert len(quilts) == 1 and np.array(Image.open(quilts[0])).shape[:2] == (16, 16)


@pytest.mark.parametrize("argv, words", [
    (["--size", "12"], ["--size 12", "WIDTHxHEIGHT"]),
    (["--effect", "Floor=shiny"], ["--effect Floor=shiny", "reflections"]),
    (["--effect", "Flor=reflections"], ["no material 'Flor'", "did you mean 'Floor'"]),
    (["--tonemap", "sepia"], ["--tonemap sepia", "aces"]),
    (["--exposure", "bright"], ["--exposure bright", "auto"]),
    (["no_such_scene"], ["no_such_scene", "built-ins"]),
    (["--views", "3", "--grid", "2x2"], ["--grid 2x2", "--views is 3"]),
    (["--set", "Shadows=2"], ["--set Shadows=2", "PASS.KEY=VALUE"]),
    (["--set", "Shadow.light_samples=2"], ["--set Shadow.light_samples=2", "did you mean 'Shadows'"]),
    (["--set", "Shadows.light_sample=2"], ["update_pass('Shadows'): pass Shadows: unknown property 'light_sample'", "'light_samples'"]),
    (["--set", "ToneMap.operator=sepia"], ["--set ToneMap.operator=sepia", "use 'aces', 'reinhard' or 'linear'"]),
])
def test_bad_options_exit_2_with_one_line_and_write_nothing(tmp_path, capsys, argv, words):
    code, out, err = run(capsys, *argv, "--size" if "--size" not in argv else "--frames", "8x8" if "--size" not in argv else "1",
                         "--out", str(tmp_path / "x.png"))
    assert code == 2
    line = err.strip()
    assert "\n" not in line and line.startswith("rayvr: error:")
    for w in words:
        assert w in line
    assert list(tmp_path.iterdir()) == []
