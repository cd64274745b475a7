"""The error study's report folder: results.json's shape, a self-contained report.html, the
images and error maps, and atomicity (a complete folder or none, also when interrupted)."""
import base64
import json
import re

import pytest

import rayvr as rv
from rayvr import Effect
from rayvr.cli.main import main
from rayvr.study import Config, Motion, ReferenceSettings, StudySettings, measure, write_report
from rayvr.study import report as report_module

SIZE = (12, 12)


@pytest.fixture(scope="module")
def results(gpu):
    scene = rv.scenes.cornell_box()
    configs = [Config("all SHADOWS", Effect.SHADOWS, options={"path_bounces": 4}),
               Config("PATH_TRACED 1 spp", Effect.PATH_TRACED, options={"spp": 1, "path_bounces": 4})]
    settings = StudySettings(frames=2, timing_frames=1, warmup=1, motion=Motion(frames=2, samples=1),
                             floor_fraction=0.1, progressive_frames=2)
    return measure(scene, configs, views=2, size=SIZE, reference=ReferenceSettings(frames=8, spp=2, max_bounces=4),
                   settings=settings, cache_dir=False, progress=False, gpu=gpu)


def test_results_json_has_the_issues_shape(results, tmp_path):
    folder = write_report(results, tmp_path / "study")
    doc = json.loads((folder / "results.json").read_text())
    assert {"reference", "rows"} <= set(doc)
    ref = doc["reference"]
    assert ref["name"] == "path-traced reference"
    assert ref["settings"]["samples_per_pixel"] == 16 and ref["settings"]["bounces"] == 4
    assert ref["convergence"]["verdict"] in ("converged", "not converged")
    assert ref["convergence"]["tolerance"] == 5e-4 and ref["convergence"]["predicted_relmse"] > 0
    assert ref["bounces"]["verdict"] in ("enough", "too few") and "relative_change_one_more" in ref["bounces"]
    assert ref["seeds"]["half_a_frames"][1] == ref["seeds"]["half_b_frames"][0]
    assert len(ref["trajectory_references"]) == 1
    assert [r["name"] for r in doc["rows"]] == ["all SHADOWS", "PATH_TRACED 1 spp"]
    for row in doc["rows"]:
        assert row["gpu_ms"] > 0 and row["frames"] == 2 and row["views"] == 2 and row["size"] == [12, 12]
        for metric in ("flip", "hdrflip", "psnr", "ssim", "relmse"):
            assert set(row[metric]) == {"mean", "std", "n"} and row[metric]["n"] == 2 * 2
            assert len(row["per_view"][metric]) == 2
        assert {"graph", "spp", "bounces", "light_samples", "frames_accumulated", "denoiser", "gi",
                "effects"} <= set(row["settings"])
        assert set(row["motion"]["flip"]) == {"mean", "std", "per_view", "n"}
        assert row["floor"]["relmse"] > 0
    assert doc["progressive"][0]["points"][-1]["frames"] == 2
    assert doc["study"]["ppd"] == pytest.approx(14.0, abs=0.05) and doc["study"]["eps"] == 0.01


def test_report_folder_holds_documents_plots_images_and_error_maps(results, tmp_path):
    folder = write_report(results, tmp_path / "study", budget_ms=2.0)
    names = {p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()}
    assert {"report.md", "report.html", "results.json", "pareto.png", "convergence.png", "images/reference.png",
            "images/reference-noise.png", "images/all-shadows.png", "images/all-shadows-flip.png",
            "images/all-shadows-relmse.png", "images/path-traced-1-spp-floor.png"} <= names
    for name in names:
        if name.endswith(".png"):
            assert (folder / name).read_bytes()[:4] == b"\x89PNG"
    md = (folder / "report.md").read_text()
    assert "| PATH_TRACED 1 spp |" in md and "path-traced reference" in md and "given array" not in md
    assert "14.0" in md and "Bias floor" in md and "(images/all-shadows-flip.png)" in md
    page = (folder / "report.html").read_text()
    sources = re.findall(r"src='([^']*)'", page)
    assert sources and all(s.startswith("data:image/png;base64,") for s in sources)      # self-contained
    assert base64.b64decode(sources[0].split(",", 1)[1])[:4] == b"\x89PNG"
    assert len(sources) == sum(n.endswith(".png") for n in names)
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]                   # no temporary left


def test_an_interrupted_report_leaves_the_old_folder_or_none(results, tmp_path, monkeypatch):
    target = tmp_path / "study"
    write_report(results, target)
    before = sorted(p.name for p in target.iterdir())

    def interrupted(*_):
        raise KeyboardInterrupt

    monkeypatch.setattr(report_module, "to_html", interrupted)   # after results.json and report.md were written
    with pytest.raises(KeyboardInterrupt):
        write_report(results, target)
    assert sorted(p.name for p in target.iterdir()) == before and (target / "report.html").stat().st_size > 0
    with pytest.raises(KeyboardInterrupt):
        write_report(results, tmp_path / "new")
    assert not (tmp_path / "new").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["study"]                         # no temporary left


def test_ctrl_c_during_the_study_exits_130_and_writes_nothing(tmp_path, monkeypatch, capsys):
    def interrupted(*_, **__):
        raise KeyboardInterrupt

    monkeypatch.setattr(rv.study, "measure", interrupted)
    rc = main(["converge", "--size", "12x12", "--views", "1", "--report", str(tmp_path / "r"), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 130 and err.count("\n") == 1 and "interrupted" in err
    assert not list(tmp_path.iterdir())


def test_report_refuses_a_file_in_its_place(results, tmp_path):
    (tmp_path / "taken").write_text("x")
    with pytest.raises(rv.OutputError, match="exists and is not a folder"):
        write_report(results, tmp_path / "taken")
