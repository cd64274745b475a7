"""`rayvr converge` and `rayvr tune`: the table, the verdict, the report folder, a user's
configurations, and refusals (exit 2, one line, nothing written)."""
import json

import pytest

from rayvr.cli.main import main
from rayvr.study.defaults import machine_defaults

TINY = ["--size", "12x12", "--views", "1", "--frames", "1", "--timing-frames", "1", "--warmup", "1",
        "--reference-frames", "4", "--reference-spp", "1", "--bounces", "2", "--motion-frames", "2",
        "--motion-samples", "1", "--progressive-frames", "2", "--spp", "1", "--floor-fraction", "0.25", "--quiet"]


def test_converge_prints_the_verdict_and_table_and_writes_the_report(gpu, tmp_path, capsys):
    report = tmp_path / "study"
    rc = main(["converge", "cornell_box", "--cache", str(tmp_path / "cache"), "--report", str(report), *TINY])
    out = capsys.readouterr().out
    assert rc == 0
    assert "reference: NOT converged" in out and "2 bounces: one more changes the mean radiance by" in out
    for row in ("| all RASTER |", "| all REFLECTIONS |", "| SHADOWS + REFLECTIONS (Floor) |", "| PATH_TRACED 1 spp |",
                "| PATH_TRACED 1 spp + TAA |"):
        assert row in out
    note = [line for line in out.splitlines() if line.startswith("defaults for")]
    d = machine_defaults(gpu)   # the defaults of the machine the test runs on
    # every size was given; what the machine's defaults still choose (llvmpipe: a coarser probe
    # grid, the hybrid levels through SVGF left out) is said in one line, or nothing is
    said = ([f"probe GI rows' probes {'x'.join(map(str, d.probe_counts))}"] if d.probe_counts else []) + \
        (["the hybrid levels through SVGF left out"] if not d.denoised_levels else [])
    if said:
        assert len(note) == 1 and note[0].split(": ", 1)[1].startswith("; ".join(said))
    else:
        assert note == []
    assert ("| all SHADOWS + SVGF |" in out) == d.denoised_levels and "| PATH_TRACED 1 spp + SVGF |" in out
    assert "against a reference that has NOT converged" in out     # the table's title says so
    assert {"report.md", "report.html", "results.json", "pareto.png", "convergence.png", "images"} == \
        {p.name for p in report.iterdir()}
    doc = json.loads((report / "results.json").read_text())
    assert doc["reference"]["convergence"]["verdict"] == "not converged"
    assert all(r["settings"]["bounces"] == 2 for r in doc["rows"])   # PATH_TRACED follows the reference
    gi = [r["settings"]["options"] for r in doc["rows"] if r["settings"]["gi"] == "probes"]
    assert gi and all(o.get("probes") == ({"counts": list(d.probe_counts)} if d.probe_counts else None)
                      for o in gi)   # the note's probe grid
    assert doc["reference"]["stop"] == "fixed" and doc["reference"]["frames"] == 4   # --reference-frames alone
    assert all({"relmse_trim", "fireflies"} <= set(r) for r in doc["rows"])
    report_md = (report / "report.md").read_text()
    assert report_md.index("**Reference**: NOT converged") < report_md.index("## Reference")   # at the top
    assert len(list((tmp_path / "cache").glob("*.npz"))) == 2 + len(doc["rows"])   # 2 references, the floors


def test_converge_takes_a_users_configurations(gpu, tmp_path, capsys):
    configs = tmp_path / "mine.json"
    configs.write_text(json.dumps({"configs": [
        {"name": "mirror floor", "effects": {"*": "shadows", "Floor": "reflections"}},
        {"name": "traced 2 spp", "effects": "path_traced", "graph": "path_traced", "options": {"spp": 2}}]}))
    rc = main(["converge", "--configs", str(configs), "--no-cache", "--no-floors", "--trajectory", "none", *TINY])
    out = capsys.readouterr().out
    assert rc == 0 and "| mirror floor |" in out and "| traced 2 spp |" in out and "| all RASTER |" not in out


def test_tune_sets_the_tuned_assignment_beside_the_uniform_rows(gpu, tmp_path, capsys):
    report = tmp_path / "tune"
    rc = main(["tune", "cornell_box", "--budget-ms", "1000", "--cache", str(tmp_path / "cache"), "--report",
               str(report), "--metric", "relmse", "--levels", "raster,shadows", "--no-floors", *TINY])
    out = capsys.readouterr().out
    assert rc == 0
    assert "| tuned for 1000 ms (tuned) |" not in out and "| tuned for 1000 ms |" in out and "| all SHADOWS |" in out
    assert "| BackWall |" in out
    doc = json.loads((report / "tune.json").read_text())
    assert doc["fits"] and doc["budget_ms"] == 1000 and doc["measured_ms"] > 0
    from rayvr.tune.budget import KNOBS
    knobs = {k.name for k in KNOBS}   # what the budget's headroom may raise after the choice
    chosen = {k: v for k, v in doc["options"].items() if k not in knobs}
    assert chosen in ({}, {"gi": "probes"}, {"denoise": "svgf"})   # --graph-options auto tried these
    assert set(doc["assignment"].values()) <= {"RASTER", "SHADOWS"} and len(doc["assignment"]) == 8
    results = json.loads((report / "results.json").read_text())
    tuned = [r for r in results["rows"] if r["tuned"]]
    assert [r["name"] for r in tuned] == ["tuned for 1000 ms"] and results["tuned"]["budget_ms"] == 1000
    assert tuned[0]["gpu_ms"] == doc["measured_ms"]
    assert "Tuned assignment" in (report / "report.md").read_text()


@pytest.mark.parametrize("command", ["converge", "tune"])
@pytest.mark.parametrize("args, message", [
    (["--size", "12"], "--size 12: expected WIDTHxHEIGHT"),
    (["--views", "0"], "--views 0: out of range; give an integer from 1 to 64"),
    (["--reference-frames", "7"], "--reference-frames 7: the reference is two equal halves"),
    (["--reference-max-frames", "9"], "--reference-max-frames 9: the reference is two equal halves"),
    (["--reference-frames", "8", "--reference-max-frames", "6"],
     "--reference-max-frames 6: fewer than the first round's 8 frames"),
    (["--reference-seconds", "-1"], "--reference-seconds -1"),
    (["--spp", "1,x"], "--spp 'x': samples per pixel must be integers"),
    (["--metrics", "flip,mse"], "--metrics flip,mse: unknown metric 'mse'"),
    (["--ppd", "-3"], "--ppd -3: out of range; give a finite number > 0 and <= 1000"),
    (["--exposure", "bright"], "--exposure bright: give stops"),
    (["--preset", "vive"], "unknown headset preset 'vive'"),
    (["--trajectory", "spin"], "--trajectory spin: use one of"),
    (["--configs", "missing.json"], "--configs missing.json: cannot read it"),
])
def test_bad_options_exit_2_with_one_line_and_write_nothing(tmp_path, capsys, command, args, message):
    report = tmp_path / "report"
    rc = main([command, "--report", str(report), "--quiet", *args])
    err = capsys.readouterr().err
    assert rc == 2 and message in err and err.count("\n") == 1
    assert not report.exists()


def test_tune_refuses_a_bad_budget_and_levels(tmp_path, capsys):
    assert main(["tune", "--budget-ms", "0"]) == 2
    assert "--budget-ms 0: out of range; give a finite number > 0 and <= 1e+06 ms" in capsys.readouterr().err
    assert main(["tune", "--levels", "raster,mirrors"]) == 2
    assert "--levels: unknown effect 'mirrors'" in capsys.readouterr().err


def test_a_bad_configs_file_names_the_entry(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps([{"name": "x", "efects": "raster"}]))
    assert main(["converge", "--configs", str(bad), *TINY]) == 2
    assert "configs[0]: unknown field 'efects' (did you mean 'effects'?)" in capsys.readouterr().err
    bad.write_text(json.dumps([{"name": "x", "effects": "mirrors"}]))
    assert main(["converge", "--configs", str(bad), *TINY]) == 2
    assert "config 'x'.effects: unknown effect 'mirrors'" in capsys.readouterr().err


def test_unknown_scene_is_refused(capsys):
    assert main(["converge", "cornel_box", *TINY]) == 2
    assert "did you mean 'cornell_box'" in capsys.readouterr().err
