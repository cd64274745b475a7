"""The trace decision's benchmarks at a smoke size on llvmpipe: `python -m benchmarks view_reuse
--quick` and `foveation --quick` run both sides, count rays and judge FLIP (whole, fovea,
eccentricity-weighted)."""
import json

from benchmarks import harness


def _rows(tmp_path, name):
    data = json.loads((tmp_path / f"{name}.json").read_text())
    return [dict(zip(data["columns"], row)) for row in data["rows"]]


def test_view_reuse_quick_reports_rays_and_flip_with_and_without(tmp_path, gpu):
    assert harness.main(["view_reuse", "--quick", "--out", str(tmp_path), "--preset", "raw"]) == 0
    rows = _rows(tmp_path, "view_reuse")
    assert [(r["views"], r["config"]) for r in rows] == [(2, "independent"), (2, "views"), (4, "independent"),
                                                         (4, "views")]
    for r in rows:
        assert r["rays_total"] > 0 and 0.0 < r["flip"] < 1.0 and 0.0 <= r["flip_fovea"] <= 1.0
        # GPU ms per pass where the driver times them: the reuse rows add the decision
        assert ("Shadows " in r["passes_ms"]) == (r["gpu_ms"] != "")
        assert ("Decision " in r["passes_ms"]) == (r["gpu_ms"] != "" and r["config"] == "views")
    reused = [r for r in rows if r["config"] == "views"]
    assert all(r["rays_other/first"] < 0.3 for r in reused)


def test_foveation_quick_reports_fewer_rays(tmp_path, gpu):
    assert harness.main(["foveation", "--quick", "--out", str(tmp_path), "--preset", "raw"]) == 0
    none, fixed = _rows(tmp_path, "foveation")
    assert none["foveation"] == "none" and fixed["foveation"] == "fixed"
    assert fixed["rays_total"] < none["rays_total"] and fixed["fewer_rays_x"] > 1.5
    assert 0.0 < fixed["flip_ecc"] < 1.0
