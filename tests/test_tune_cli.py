"""`rayvr tune`: the table, the assignment, the report folder, and refusals (exit 2, nothing written)."""
import json

import pytest

from rayvr.cli.main import main

TINY = ["--size", "12x12", "--views", "1", "--frames", "1", "--warmup", "1", "--spp", "1",
        "--reference-frames", "2", "--reference-spp", "1", "--levels", "raster,shadows", "--quiet"]


def test_tune_prints_table_and_assignment_and_writes_the_report(gpu, tmp_path, capsys):
    report = tmp_path / "report"
    rc = main(["tune", "cornell_box", "--budget-ms", "1000", "--cache", str(tmp_path / "cache"),
               "--report", str(report), "--metric", "relmse", *TINY])
    out = capsys.readouterr().out
    assert rc == 0
    for row in ("| all RASTER |", "| all SHADOWS |", "| SHADOWS + REFLECTIONS (Floor) |", "| PATH_TRACED 1 spp |",
                "| tuned for 1000 ms |", "| BackWall |"):
        assert row in out
    assert {p.name for p in report.iterdir()} == {"table.md", "results.csv", "results.json", "assignment.md",
                                                  "tune.json", "error_vs_ms_flip.png", "error_vs_ms_relmse.png",
                                                  "error_vs_ms_psnr.png"}
    doc = json.loads((report / "tune.json").read_text())
    assert doc["fits"] and doc["budget_ms"] == 1000 and doc["measured_ms"] > 0
    assert set(doc["assignment"].values()) <= {"RASTER", "SHADOWS"}
    assert len(doc["assignment"]) == 8 and doc["model"]["metric"] == "relmse"
    assert len(list((tmp_path / "cache").glob("*.npz"))) == 1


@pytest.mark.parametrize("args, message", [
    (["--budget-ms", "0"], "--budget-ms 0: out of range; give a finite number > 0 and <= 1e+06 ms"),
    (["--size", "12"], "--size 12: expected WIDTHxHEIGHT"),
    (["--views", "0"], "--views 0: out of range; give an integer from 1 to 64"),
    (["--levels", "raster,mirrors"], "--levels: unknown effect 'mirrors'"),
    (["--spp", "1,x"], "--spp 'x': samples per pixel must be integers"),
    (["--metrics", "flip,ssim"], "--metrics flip,ssim: unknown metric 'ssim'"),
    (["--ppd", "-3"], "--ppd -3: out of range; give a finite number > 0 and <= 1000"),
])
def test_bad_options_exit_2_with_one_line_and_write_nothing(tmp_path, capsys, args, message):
    report = tmp_path / "report"
    rc = main(["tune", "--report", str(report), *args])
    err = capsys.readouterr().err
    assert rc == 2 and message in err and err.count("\n") == 1
    assert not report.exists()


def test_unknown_scene_is_refused(tmp_path, capsys):
    assert main(["tune", "cornel_box", *TINY]) == 2
    assert "did you mean 'cornell_box'" in capsys.readouterr().err
