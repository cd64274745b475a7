"""The CLI against misuse: options out of range, unwritable outputs (refused before rendering),
failures and Ctrl-C while writing (all or nothing), view grids and quilts, `rayvr check`."""
import errno
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import rayvr as rv
import rayvr.cli.render
import rayvr.renderer
from rayvr.cli.main import main
from rayvr.fileio import atomic_group, check_writable, write_text
from rayvr.xr.cameras import default_views, grid_for_views

TINY = ["--size", "8x8"]


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def files(folder):
    """Every file under `folder`, hidden ones included."""
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*")) if folder.exists() else []


def one_error_line(err, *words):
    line = err.strip()
    assert "\n" not in line and line.startswith("rayvr: error:"), err
    for w in words:
        assert w in line, f"{w!r} not in {line!r}"
    return line


@pytest.fixture
def no_rendering(monkeypatch):
    """Fail the test if a Renderer is ever made: the refusal must come before any rendering."""
    def refuse(*args, **kwargs):
        raise AssertionError("a Renderer was created before the bad input was refused")
    monkeypatch.setattr(rv.renderer.Renderer, "__init__", refuse)


# --- options: every numeric option refuses NaN, infinities, negatives, out-of-range values ------
MISUSES = [
    (["render", "--ipd", "-1"], ["--ipd -1", "> 0 and <= 1 metres"]),
    (["render", "--environment", "-1,1,1"], ["--environment: expected one argument", "after '='"]),
    (["render", "--environment=-1,1,1"], ["--environment", "-1"]),
    (["render", "--ipd", "nan"], ["--ipd nan", "finite number"]),
    (["render", "--ipd", "inf"], ["--ipd inf", "finite number"]),
    (["render", "--ipd", "2"], ["--ipd 2", "<= 1 metres"]),
    (["render", "--max-bounces", "-1"], ["--max-bounces -1", "from 1 to 64"]),
    (["render", "--max-bounces", "0"], ["--max-bounces 0", "from 1 to 64"]),
    (["render", "--light-samples", "0"], ["--light-samples 0", "from 1 to 256"]),
    (["render", "--frames", "0"], ["--frames 0", "from 1 to 100000"]),
    (["render", "--frames", "many"], ["--frames many", "expected an integer"]),
    (["render", "--views", "0"], ["--views 0", "from 1 to 64"]),
    (["render", "--views", "65"], ["--views 65", "from 1 to 64"]),
    (["render", "--views", "2.5"], ["--views 2.5", "expected an integer"]),
    (["render", "--size", "0x10"], ["--size 0x10", "WIDTHxHEIGHT"]),
    (["render", "--size", "9000x10"], ["--size 9000x10", "at most 8192"]),
    (["render", "--size", "4096x4096", "--views", "64"], ["--size 4096x4096 with --views 64", "fewer views"]),
    (["tune", "--spp", "1,100000"], ["--spp '100000'", "from 1 to 1024"]),
    (["render", "--exposure", "nan"], ["--exposure nan", "-64 to 64"]),
    (["render", "--exposure", "100"], ["--exposure 100", "-64 to 64"]),
    (["render", "--view-cone", "0"], ["--view-cone 0", "> 0 and < 180 degrees"]),
    (["render", "--view-cone", "180"], ["--view-cone 180", "> 0 and < 180 degrees"]),
    (["render", "--views", "3", "--grid", "2x2"], ["--grid 2x2 has 4 views", "--views is 3", "--grid 3x1"]),
    (["render", "--views", "4", "--grid", "two"], ["--grid 'two'", "COLSxROWS"]),
    (["render", "--views", "4", "--quilt", "q.bmp"], ["--quilt q.bmp", "unknown image type '.bmp'"]),
    (["render", "--views", "1", "--quilt", "q.png"], ["--quilt", "2 or more views", "--views is 1"]),
    (["render", "--quilt-suffix"], ["--quilt-suffix", "--quilt FILE"]),
    (["render", "--out", "x.tiff"], ["--out x.tiff", ".png or .jpg", ".exr"]),
    (["render", "--layout", "diagonal"], ["argument --layout", "invalid choice: 'diagonal'"]),
    (["render", "--no-such-option"], ["unrecognized arguments: --no-such-option"]),
    (["render", "--set", "Shadows.light_samples=NaN"], ["--set Shadows.light_samples=NaN", "must be a finite number"]),
    (["render", "--set", "ToneMap.exposure=1e999"], ["--set ToneMap.exposure=1e999", "must be a finite number"]),
    (["render", "--set", "Shadows.light_samples=-3"], ["--set Shadows.light_samples=-3", "from 1 to 256"]),
    (["render", "--set", "Reflections.max_bounces=0"], ["--set Reflections.max_bounces=0", "from 1 to 64"]),
    (["render", "--gi", "probes", "--set", "Probes.counts=[1000,1000,1000]"],
     ["--set Probes.counts=[1000,1000,1000]", "each 1 to 32"]),
    (["tune", "--budget-ms", "nan"], ["--budget-ms nan", "finite number > 0"]),
    (["tune", "--budget-ms", "-1"], ["--budget-ms -1", "> 0"]),
    (["tune", "--frames", "0"], ["--frames 0", "from 1 to 100000"]),
    (["tune", "--warmup", "-1"], ["--warmup -1", "from 0 to 100000"]),
    (["tune", "--reference-spp", "0"], ["--reference-spp 0", "from 1 to 1024"]),
    (["tune", "--ppd", "inf"], ["--ppd inf", "finite number > 0"]),
    (["tune", "--views", "100"], ["--views 100", "from 1 to 64"]),
    (["tune", "--workers", "0"], ["--workers 0", "from 1 to 1024"]),
    (["converge", "--bounces", "0"], ["--bounces 0", "from 1 to 64"]),
    (["converge", "--tonemap", "nope"], ["--tonemap nope", "aces, reinhard, linear"]),
    (["converge", "--no-cache", "--cache", "refs"], ["--cache refs with --no-cache", "leave one of them out"]),
    (["converge", "--preset", "nope"], ["--preset nope", "index"]),
    (["converge", "--tolerance", "nan"], ["--tolerance nan", "finite number > 0"]),
    (["converge", "--warmup-s", "-1"], ["--warmup-s -1", ">= 0 and <= 3600 s"]),
    (["converge", "--motion-samples", "300"], ["--motion-samples 300", "from 1 to 255"]),
    (["converge", "--reference-frames", "0"], ["--reference-frames 0", "from 2 to 1048576"]),
    (["converge", "--exposure", "inf"], ["--exposure inf", "-64 to 64"]),
    (["converge", "--size", "4096x4096", "--views", "64"], ["--size 4096x4096 with --views 64", "fewer views"]),
    (["graph", "show", "g.json", "--views", "0"], ["--views 0", "from 1 to 64"]),
    (["graph", "show", "g.json", "--png", "g.gif"], ["g.gif", ".png, .svg or .pdf"]),
    (["graph", "show", "missing.json"], ["missing.json"]),
    (["check", "--frames", "0"], ["--frames 0", "from 1 to 1000"]),
    (["check", "--size", "1x0"], ["--size 1x0", "WIDTHxHEIGHT"]),
    (["no-such-command"], ["invalid choice: 'no-such-command'"]),
]


@pytest.mark.parametrize("argv, words", MISUSES, ids=[" ".join(a) for a, _ in MISUSES])
def test_misuse_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys, monkeypatch, no_rendering, argv, words):
    monkeypatch.chdir(tmp_path)
    out_args = {"render": ["--out", str(tmp_path / "out" / "x.png")] if "--out" not in argv else [],
                "tune": ["--report", str(tmp_path / "out" / "report")],
                "converge": ["--report", str(tmp_path / "out" / "report")],
                "check": ["--masks", str(tmp_path / "out" / "masks")]}.get(argv[0], [])
    code, out, err = run(capsys, *argv, *out_args)
    assert code == 2, (out, err)
    one_error_line(err, *words)
    assert files(tmp_path) == []


def test_there_are_at_least_twenty_misuses():
    assert len(MISUSES) >= 20


# --- unwritable outputs: refused before any rendering, one line, nothing written ----------------
def _under_a_file(tmp_path):
    (tmp_path / "plain.txt").write_text("a regular file")
    return tmp_path / "plain.txt" / "sub"


@pytest.mark.parametrize("where", ["proc", "under a file", "read-only"])
@pytest.mark.parametrize("command", ["render", "render --quilt", "tune --report", "tune --cache", "converge --report",
                                     "graph --png", "check --masks"])
def test_unwritable_output_is_refused_before_rendering(tmp_path, capsys, monkeypatch, no_rendering, command, where):
    if where == "proc" and not Path("/proc/self").exists():
        pytest.skip("no /proc here")
    base = {"proc": Path("/proc"), "under a file": _under_a_file(tmp_path), "read-only": tmp_path / "ro"}[where]
    if where == "read-only":
        def read_only(*args, **kwargs):
            raise OSError(errno.EROFS, "Read-only file system")
        monkeypatch.setattr(tempfile, "mkstemp", read_only)
    graph = tmp_path / "g.json"
    graph.write_text('{"name": "G", "passes": [], "edges": [], "outputs": []}')
    argv = {"render": ["render", *TINY, "--out", str(base / "x.png")],
            "render --quilt": ["render", *TINY, "--views", "4", "--out", str(tmp_path / "ok" / "x.png"),
                               "--quilt", str(base / "q.png")],
            "tune --report": ["tune", *TINY, "--quiet", "--report", str(base / "report")],
            "tune --cache": ["tune", *TINY, "--quiet", "--cache", str(base / "cache")],
            "converge --report": ["converge", *TINY, "--quiet", "--report", str(base / "report")],
            "graph --png": ["graph", "show", str(graph), "--png", str(base / "g.png")],
            "check --masks": ["check", "--masks", str(base / "masks")]}[command]
    before = files(tmp_path)
    code, out, err = run(capsys, *argv)
    assert code == 2, (out, err)
    option = {"render": "--out", "render --quilt": "--quilt", "tune --report": "--report", "tune --cache": "--cache",
              "converge --report": "--report", "graph --png": "--png", "check --masks": "--masks"}[command]
    if where == "read-only" and command == "render --quilt":
        option = "--out"   # the whole file system refuses: the first output checked is named
    reason = {"proc": "cannot create files in /proc", "under a file": "is a file, not a folder",
              "read-only": "Read-only file system"}[where]
    one_error_line(err, option, reason)
    assert files(tmp_path) == before


@pytest.mark.parametrize("argv, words", [
    (["--set", "Nope.x=1"], ["--set Nope.x=1", "no pass 'Nope'"]),
    (["--set", "Shadows.light_samples=Infinity"], ["--set Shadows.light_samples=Infinity", "finite number"]),
    (["--foveal-radius", "5"], ["--foveal-radius", "add --foveation fixed or gaze"]),
])
def test_a_bad_graph_option_is_refused_before_the_scene_loads_and_warns(tmp_path, capsys, monkeypatch, argv, words):
    def refuse(*args, **kwargs):
        raise AssertionError("the scene was loaded (and its warnings printed) before the bad option was refused")
    monkeypatch.setattr(rayvr.cli.render, "load_scene_arg", refuse)
    code, out, err = run(capsys, "render", *TINY, "--out", str(tmp_path / "x.png"), *argv)
    assert code == 2, (out, err)
    one_error_line(err, *words)
    assert files(tmp_path) == []


def test_written_files_and_report_folders_get_the_usual_mode_not_a_private_one(tmp_path):
    from rayvr.fileio import atomic_folder

    mask = os.umask(0o022)
    try:
        write_text(tmp_path / "new.txt", "a")
        with atomic_group():
            write_text(tmp_path / "pair_L.txt", "l")
            write_text(tmp_path / "pair_R.txt", "r")
        with atomic_folder(tmp_path / "report") as folder:
            (folder / "report.md").write_text("# r")
        (tmp_path / "kept.txt").write_text("old")
        os.chmod(tmp_path / "kept.txt", 0o640)
        write_text(tmp_path / "kept.txt", "new")
    finally:
        os.umask(mask)
    mode = {name: (tmp_path / name).stat().st_mode & 0o777 for name in
            ("new.txt", "pair_L.txt", "pair_R.txt", "report", "kept.txt")}
    assert mode == {"new.txt": 0o644, "pair_L.txt": 0o644, "pair_R.txt": 0o644, "report": 0o755,
                    "kept.txt": 0o640}   # a replaced file keeps its mode
    assert (tmp_path / "kept.txt").read_text() == "new"


def test_check_writable_accepts_a_new_folder_and_leaves_no_probe(tmp_path):
    check_writable(tmp_path / "a" / "b" / "c.png", "--out")
    check_writable(tmp_path / "report", "--report", folder=True)
    assert files(tmp_path) == []
    with pytest.raises(rv.OutputError, match="is a folder; name a file"):
        check_writable(tmp_path, "--out")


# --- all or nothing -------------------------------------------------------------------------------
def _fail_on(monkeypatch, module, name, n, exc):
    """Make the n-th call of module.name raise `exc` (earlier calls go through)."""
    original = getattr(module, name)
    calls = []

    def wrapper(*args, **kwargs):
        calls.append(1)
        if len(calls) == n:
            raise exc
        return original(*args, **kwargs)
    monkeypatch.setattr(module, name, wrapper)
    return calls


def test_a_failed_rename_in_a_stereo_render_keeps_the_previous_pair(gpu, tmp_path, capsys, monkeypatch):
    out = tmp_path / "out"
    assert run(capsys, "render", *TINY, "--exposure", "0", "--out", str(out / "c.png"))[0] == 0
    old = {p: p.read_bytes() for p in out.iterdir()}
    assert set(p.name for p in old) == {"c_L.png", "c_R.png"}
    _fail_on(monkeypatch, os, "replace", 4, OSError(errno.ENOSPC, "No space left on device"))
    code, _, err = run(capsys, "render", *TINY, "--exposure", "3", "--out", str(out / "c.png"))
    assert code == 2
    one_error_line(err, "c_R.png", "No space left on device", "nothing was written")
    assert {p: p.read_bytes() for p in out.iterdir()} == old       # the old pair, no temporaries


@pytest.mark.parametrize("failure, words", [
    (OSError(errno.ENOSPC, "No space left on device"), ["x_v2.png", "No space left on device"]),
    (KeyboardInterrupt(), ["interrupted"]),
])
def test_a_grid_render_that_fails_while_writing_leaves_no_view(gpu, tmp_path, capsys, monkeypatch, failure, words):
    _fail_on(monkeypatch, Image.Image, "save", 3, failure)
    code, _, err = run(capsys, "render", "--views", "6", "--size", "4x4", "--out", str(tmp_path / "out" / "x.png"))
    if isinstance(failure, KeyboardInterrupt):
        assert (code, err) == (130, "rayvr: interrupted\n")
    else:
        assert code == 2
        one_error_line(err, *words)
    assert files(tmp_path) == []                                       # not even the folder


def test_atomic_group_undoes_renames_and_restores_replaced_files(tmp_path, monkeypatch):
    keep = tmp_path / "b.txt"
    keep.write_text("old b")
    _fail_on(monkeypatch, os, "replace", 4, KeyboardInterrupt())      # a: 1 rename; b: aside + rename; c: fails
    with pytest.raises(KeyboardInterrupt):
        with atomic_group():
            for name in "abc":
                write_text(tmp_path / name / ".." / f"{name}.txt", f"new {name}")
    assert files(tmp_path) == ["b.txt"] and keep.read_text() == "old b"
    monkeypatch.undo()
    with atomic_group():                                              # and when nothing fails
        write_text(tmp_path / "new" / "a.txt", "a")
        with atomic_group():                                          # nested groups join the outer one
            write_text(tmp_path / "new" / "b.txt", "b")
        assert not (tmp_path / "new" / "a.txt").exists()
    assert files(tmp_path / "new") == ["a.txt", "b.txt"]


def test_a_tune_report_that_fails_half_way_leaves_no_report(gpu, tmp_path, capsys, monkeypatch):
    report = tmp_path / "report"
    _fail_on(monkeypatch, Path, "write_text", 1, OSError(errno.EIO, "Input/output error"))   # results.json
    code, _, err = run(capsys, "tune", "--size", "8x8", "--views", "1", "--frames", "1", "--warmup", "0", "--spp", "1",
                       "--reference-frames", "2", "--reference-spp", "1", "--levels", "raster", "--metrics", "relmse",
                       "--metric", "relmse", "--graph-options", "none", "--quiet", "--cache", str(tmp_path / "cache"),
                       "--report", str(report))
    assert code == 2, err
    one_error_line(err, "results.json", "Input/output error")
    assert not report.exists()


# --- Ctrl-C anywhere: one line, exit 130, nothing partial ---------------------------------------------
def _interrupt(*args, **kwargs):
    raise KeyboardInterrupt


@pytest.mark.parametrize("target", ["render", "write", "rename", "tune", "graph", "graph png", "check"])
def test_ctrl_c_is_one_line_exit_130_and_leaves_nothing(gpu, tmp_path, capsys, monkeypatch, target):
    import rayvr.check
    import rayvr.tune.cost_probe
    from rayvr.rendergraph.graph import RenderGraph

    graph = tmp_path / "in" / "g.json"
    rv.graphs.hybrid(preset="raw").save(graph)
    out = tmp_path / "out"
    argv = ["render", *TINY, "--out", str(out / "x.png")]
    if target == "render":
        monkeypatch.setattr(rv.renderer.Renderer, "render", _interrupt)
    elif target == "write":
        _fail_on(monkeypatch, Image.Image, "save", 2, KeyboardInterrupt())
    elif target == "rename":
        _fail_on(monkeypatch, os, "replace", 2, KeyboardInterrupt())
    elif target == "tune":
        monkeypatch.setattr(rayvr.tune.cost_probe, "probe_cost_model", _interrupt)
        argv = ["tune", *TINY, "--quiet", "--report", str(out / "report"), "--no-cache"]   # Ctrl-C in the probe
    elif target == "graph":
        monkeypatch.setattr(RenderGraph, "compile", _interrupt)
        argv = ["graph", "show", str(graph), "--scene", "cornell_box", "--png", str(out / "g.png")]
    elif target == "graph png":
        import matplotlib.figure

        monkeypatch.setattr(matplotlib.figure.Figure, "savefig", _interrupt)
        monkeypatch.setattr("shutil.which", lambda name: None)       # the matplotlib drawing
        argv = ["graph", "show", str(graph), "--scene", "cornell_box", "--png", str(out / "g.png")]
    else:
        monkeypatch.setattr(rayvr.check, "run_check", _interrupt)
        argv = ["check", "--masks", str(out / "masks")]
    code, _, err = run(capsys, *argv)
    assert (code, err) == (130, "rayvr: interrupted\n")
    assert files(out) == [] and files(tmp_path) == ["in", "in/g.json"]


# --- views without --grid, and quilts --------------------------------------------------------------
def test_grid_for_views_is_the_most_square_factorisation():
    assert [grid_for_views(n) for n in (1, 3, 4, 6, 7, 12, 45, 48, 64)] == \
        [(1, 1), (3, 1), (2, 2), (3, 2), (7, 1), (4, 3), (9, 5), (8, 6), (8, 8)]
    for n in range(1, 65):
        cols, rows = grid_for_views(n)
        assert cols * rows == n and cols >= rows


def test_views_without_grid_render_a_grid_of_that_many(gpu, tmp_path, capsys):
    views = default_views(rv.scenes.cornell_box(), 48, (4, 4))
    xs = sorted({round(float(v.pose.position[0]), 9) for v in views})
    ys = sorted({round(float(v.pose.position[1]), 9) for v in views})
    assert (len(views), len(xs), len(ys)) == (48, 8, 6)
    code, out, err = run(capsys, "render", "--views", "5", "--size", "4x4", "--out", str(tmp_path / "v.png"))
    assert code == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"v_v{i}.png" for i in range(5)]


def _record_quilt_views(monkeypatch):
    import rayvr.xr.quilt as quilt

    seen = []
    original = quilt.quilt_views
    monkeypatch.setattr(quilt, "quilt_views", lambda *a, **k: seen.append(original(*a, **k)) or seen[-1])
    return seen


def test_quilt_is_written_to_exactly_its_path_from_one_horizontal_row(gpu, tmp_path, capsys, monkeypatch):
    seen = _record_quilt_views(monkeypatch)
    code, out, err = run(capsys, "render", "--views", "6", "--size", "4x4", "--layout", "side-by-side",
                         "--out", str(tmp_path / "sbs.png"), "--quilt", str(tmp_path / "q.jpg"))
    assert code == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["q.jpg", "sbs.png"]
    assert (tmp_path / "q.jpg").read_bytes()[:2] == b"\xff\xd8"              # JPEG, as the name says
    assert Image.open(tmp_path / "q.jpg").size == (3 * 4, 2 * 4)            # 3x2 tiles of 4x4
    assert f"wrote {tmp_path / 'q.jpg'} (quilt of 3x2 tiles" in out
    # the six cameras lie on one horizontal line, left to right (a Looking Glass has no vertical parallax)
    pos = np.array([v.pose.position for v in seen[0]])
    assert np.allclose(pos[:, 1:], pos[0, 1:]) and (np.diff(pos[:, 0]) > 0).all()


def test_quilt_suffix_appends_the_looking_glass_name(gpu, tmp_path, capsys):
    code, out, err = run(capsys, "render", "--views", "4", "--size", "8x4", "--out", str(tmp_path / "v.png"),
                         "--quilt", str(tmp_path / "q.png"), "--quilt-suffix")
    assert code == 0, err
    assert (tmp_path / "q_qs2x2a2.png").exists() and not (tmp_path / "q.png").exists()


# --- rayvr check -----------------------------------------------------------------------------------
def test_check_passes_a_finite_scene(gpu, capsys):
    code, out, err = run(capsys, "check", "quad", "--size", "8x8", "--views", "1", "--frames", "1")
    assert code == 0, err
    for config in ("hybrid RASTER: ok", "hybrid_taa PATH_TRACED: ok", "path_traced: ok"):
        assert config in out
    assert "  GBuffer: posW 0," in out and "warnings: 0" in out


def test_check_finds_a_nan_names_its_pass_and_writes_where(gpu, tmp_path, capsys, monkeypatch):
    from rayvr.passes import DirectLighting

    original = DirectLighting.execute

    def poisoned(self, ctx, data):
        original(self, ctx, data)
        tex = data["direct"]
        texel = np.zeros(4, {"f2": np.float16, "f4": np.float32}[tex.dtype])
        texel[0] = np.nan
        tex.write(texel.tobytes(), viewport=(5, 6, 1, 1, 1, 1))          # x 5, y 6 (GL rows), view 1

    monkeypatch.setattr(DirectLighting, "execute", poisoned)
    masks = tmp_path / "masks"
    code, out, err = run(capsys, "check", "quad", "--size", "8x8", "--views", "2", "--frames", "1",
                         "--masks", str(masks))
    assert code == 1, err
    assert "hybrid RASTER:" in out and "  Direct: direct 1" in out
    mask = np.array(Image.open(masks / "hybrid_RASTER-Direct-direct.png"))[..., 0]
    assert mask.shape == (8, 16)                                             # two views side by side
    assert list(zip(*np.nonzero(mask))) == [(8 - 1 - 6, 8 + 5)]              # top-down row, view 1's column


def test_check_counts_the_samples_a_pass_scrubbed_as_a_fault(gpu, capsys, monkeypatch):
    """A NaN a pass set to 0 leaves its output finite; its GPU counter still fails the check (the
    counters themselves are tested in test_nonfinite_counts.py)."""
    from rayvr.rendergraph.compiled import CompiledGraph

    monkeypatch.setattr(CompiledGraph, "nonfinite_counts",
                        lambda self: {p: (3 if p == "Direct" else 0) for p in self.nonfinite.slot})
    code, out, err = run(capsys, "check", "quad", "--size", "8x8", "--views", "1", "--frames", "1")
    assert code == 1, err
    assert "hybrid RASTER: 3 non-finite values" in out
    assert "scrubbed samples 3" in out and "give --masks DIR" not in out
