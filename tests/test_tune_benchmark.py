"""`python -m benchmarks error_vs_time --quick`: rows per configuration and the plots."""
import json

from benchmarks import harness


def test_error_vs_time_quick_writes_rows_and_plots(gpu, tmp_path):
    rc = harness.main(["error_vs_time", "--quick", "--out", str(tmp_path), "--views", "1", "--spp", "1",
                       "--reference-spp", "1", "--cache", str(tmp_path / "cache")])
    assert rc == 0
    doc = json.loads((tmp_path / "error_vs_time.json").read_text())
    assert doc["columns"] == ["config", "views x size", "GPU ms", "FLIP", "relMSE", "PSNR dB"]
    names = [row[0] for row in doc["rows"]]
    assert names == ["all RASTER", "all SHADOWS", "SHADOWS + REFLECTIONS (Floor)", "PATH_TRACED 1 spp"]
    for row in doc["rows"]:
        assert row[1] == "1x32x32" and row[2] > 0 and 0 < row[3] < 1 and row[4] > 0
    for metric in ("flip", "relmse", "psnr"):
        assert (tmp_path / f"error_vs_time_{metric}.png").read_bytes()[:4] == b"\x89PNG"
