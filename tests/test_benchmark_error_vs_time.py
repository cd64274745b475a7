"""`python -m benchmarks error_vs_time --quick`: a row per configuration and tuned budget, and
the study's report folder per scene."""
import json

from benchmarks import harness


def test_error_vs_time_quick_writes_rows_tuned_budgets_and_the_report(gpu, tmp_path):
    rc = harness.main(["error_vs_time", "--quick", "--out", str(tmp_path), "--views", "1", "--size", "12x12",
                       "--frames", "1", "--timing-frames", "1", "--warmup", "1", "--reference-frames", "4",
                       "--reference-spp", "1", "--motion-frames", "2", "--motion-samples", "1",
                       "--progressive-frames", "2", "--budgets", "1000,0.001", "--cache", str(tmp_path / "cache")])
    assert rc == 0
    doc = json.loads((tmp_path / "error_vs_time.json").read_text())
    assert doc["columns"][:5] == ["scene", "config", "views x size", "GPU ms", "FLIP"]
    names = [row[1] for row in doc["rows"]]
    assert names[:2] == ["all RASTER", "all SHADOWS"] and names[-2:] == ["tuned for 1000 ms", "tuned for 0.001 ms"]
    assert "PATH_TRACED 16 spp" in names
    for row in doc["rows"]:
        assert row[0] == "cornell_box" and row[2] == "1x12x12" and row[3] > 0
        assert " ± " in row[4] and 0 < float(row[4].split(" ± ")[0]) < 1
    assert any("tuned for 0.001 ms" in n and "exceeds" in n for n in doc["notes"])
    report = tmp_path / "error_vs_time_cornell-box"
    assert (report / "report.html").exists() and json.loads((report / "results.json").read_text())["rows"]
