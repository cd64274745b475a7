"""`python -m benchmarks NAME --quick` writes JSON and appends markdown rows with the environment."""
import json
import sys
from pathlib import Path


sys.path.insert(0, str(Path(__file__).resolve().parents[1]))   # the repository root holds benchmarks/

from benchmarks import harness  # noqa: E402


def test_aliasing_quick_run_records_json_and_markdown(tmp_path, gpu, capsys):
    assert harness.main(["aliasing", "--quick", "--out", str(tmp_path)]) == 0
    assert harness.main(["aliasing", "--quick", "--out", str(tmp_path), "--passes", "4"]) == 0
    doc = json.loads((tmp_path / "aliasing.json").read_text())
    assert doc["device"] == gpu.caps.renderer and doc["driver"] == gpu.caps.version
    assert doc["commit"] and doc["date"].endswith("UTC") and doc["software"] == gpu.caps.is_software
    row = dict(zip(doc["columns"], doc["rows"][0]))
    assert row["passes"] == 4 and row["gpu_objects"] == 3 and row["fraction"] == 0.75
    md = (tmp_path / "aliasing.md").read_text().splitlines()
    assert md[0] == "# benchmark: aliasing" and sum(line.startswith("| date |") for line in md) == 1
    rows = [line for line in md if line.startswith("| 20")]
    assert len(rows) == 2 and all("(quick)" in r for r in rows)
    assert ("(software)" in rows[0]) == gpu.caps.is_software
    first = dict(zip(doc["columns"], rows[0].strip("| ").split(" | ")[4:]))
    assert first["fraction"] == "0.3" and first["meets"] == "yes"


def test_rows_with_other_columns_start_a_new_table(tmp_path):
    env = {"device": "d", "software": False, "driver": "v", "date": "2026-11-22 00:00 UTC", "commit": "abc"}
    harness.record("t", {"columns": ["a"], "rows": [[1]]}, env, {}, tmp_path)
    harness.record("t", {"columns": ["a"], "rows": [[2]]}, env, {}, tmp_path)
    harness.record("t", {"columns": ["a", "b"], "rows": [[3, 4]]}, env, {}, tmp_path)
    md = (tmp_path / "t.md").read_text().splitlines()
    heads = [i for i, line in enumerate(md) if line.startswith("| date |")]
    assert [md[i] for i in heads] == ["| date | commit | device | driver | a |",
                                      "| date | commit | device | driver | a | b |"]
    assert md[heads[1] + 2] == "| 2026-11-22 00:00 UTC | abc | d | v | 3 | 4 |"
    assert sum(line.startswith("| 2026") for line in md[:heads[1]]) == 2


def test_graph_overhead_quick_has_all_settings(tmp_path, gpu):
    # --no-save with --out: the folder it would write to stays empty
    assert harness.main(["graph_overhead", "--quick", "--no-save", "--out", str(tmp_path), "--passes", "3"]) == 0
    assert not list(tmp_path.iterdir())
    harness.main(["graph_overhead", "--quick", "--out", str(tmp_path), "--passes", "3"])
    doc = json.loads((tmp_path / "graph_overhead.json").read_text())
    kinds = [(r[0], r[1]) for r in doc["rows"]]
    assert kinds == [("empty passes", "off"), ("Clear+Blits", "off"), ("Clear+Blits", "on")]
    empty = dict(zip(doc["columns"], doc["rows"][0]))
    assert empty["meets"] == "yes" and empty["mean_ms"] < 0.3


def test_unknown_benchmark_suggests(capsys):
    assert harness.main(["alising"]) == 2
    assert "unknown benchmark 'alising' (did you mean 'aliasing'?)" in capsys.readouterr().err
    assert {"aliasing", "graph_overhead"} <= set(harness.available())


def test_rays_diffuse_layouts_trace_the_same_rays(tmp_path, gpu):
    """The queue and the persistent layout (lanes refilled through rq_begin/rq_step with subgroup
    ballots) trace exactly the rays of the every-pixel dispatch: same hits, same node counts."""
    rows = {}
    for layout in ("pixels", "queue", "persistent"):
        harness.main(["rays", "--quick", "--out", str(tmp_path / layout), "--diffuse-layout", layout,
                      "--diffuse-per-hit", "2", "--stats"])
        doc = json.loads((tmp_path / layout / "rays.json").read_text())
        rows[layout] = dict(zip(doc["columns"], doc["rows"][0]))
    assert 0.05 < rows["pixels"]["diffuse_hit_frac"] < 1.0
    for layout in ("queue", "persistent"):
        for col in ("primary_hit_frac", "diffuse_hit_frac", "diffuse_nodes", "diffuse_tris", "diffuse_instances"):
            assert rows[layout][col] == rows["pixels"][col], (layout, col)


def test_restir_quick_rows_and_its_bad_sets(tmp_path, gpu, capsys):
    """`benchmarks restir` on the Cornell box: RTShadows' row, a row and a ratio row per ReSTIR
    set (named, or JSON properties), finite errors, its progress on stderr; a set that is not JSON or
    not a name is one line and exit 2."""
    args = ["restir", "--quick", "--scene", "cornell_box", "--parts", "scene", "--out", str(tmp_path)]
    assert harness.main([*args, "--restir", "2 candidates, auto hints"]) == 0
    doc = json.loads((tmp_path / "restir.json").read_text())
    configs = [dict(zip(doc["columns"], r))["config"] for r in doc["rows"]]
    assert configs == ["RTShadows light_samples=1", "ReSTIRDI 2 candidates", "ReSTIR / plain SHADOWS: FLIP, frame ms",
                       "ReSTIRDI auto hints", "ReSTIR / plain SHADOWS: FLIP, frame ms"]
    for row in (dict(zip(doc["columns"], r)) for r in doc["rows"][:2]):
        assert 0 < row["FLIP"] < 1 and 0 <= row["relMSE"] < 10
    assert "restir:" in capsys.readouterr().err   # the progress bar
    assert harness.main([*args, "--restir", '{"target": "cosine"}']) == 0
    doc = json.loads((tmp_path / "restir.json").read_text())
    assert [dict(zip(doc["columns"], r))["config"] for r in doc["rows"]][1] == 'ReSTIRDI {"target": "cosine"}'
    capsys.readouterr()
    for bad, says in (("{candidates: 2}", "--restir: not JSON"), ("lean, slim", "--restir: no set 'slim'")):
        assert harness.main([*args, "--restir", bad]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"python -m benchmarks restir: error: {says}"), err
