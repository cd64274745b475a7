"""Save/load round trips (Python script and JSON), JSON errors by file and field, registry,
pictures, and `rayvr graph show`."""
import json

import pytest

from rayvr.cli.main import main as cli
from rayvr.errors import GraphError
from rayvr.passes.basic import Blit, Checkerboard, Clear
from rayvr.rendergraph import RenderGraph, get_pass_class, register_pass, registered_passes


def sample():
    g = RenderGraph("Sample")
    g.addPass(Checkerboard({"cell": 3, "color_a": [1, 0, 0, 1]}), "Pattern")
    g.addPass(Clear(view_colors=[[0, 1, 0, 1], [0, 0, 1, 1]]), "Background")
    g.addPass(Blit({"scale": 0.5, "format": "rgba16f", "filter": "nearest"}), "Half")
    g.addPass(Clear(), "Unused")
    g.addEdge("Pattern.dst", "Half.src")
    g.addEdge("Background", "Pattern")
    g.markOutput("Half.dst")
    g.markOutput("Background.dst")
    return g


def same_graph(a, b):
    assert a.name == b.name
    assert list(a.passes) == list(b.passes)
    for name, p in a.passes.items():
        q = b.passes[name]
        assert type(p) is type(q) and p.get_properties() == q.get_properties() and q.name == name
    assert [(e.src, e.dst) for e in a.edges] == [(e.src, e.dst) for e in b.edges]
    assert a.outputs == b.outputs
    pa, pb = a.plan(size=(8, 8), views=2), b.plan(size=(8, 8), views=2)
    assert pa.order == pb.order == ["Background", "Pattern", "Half"] and pa.pruned == pb.pruned


@pytest.mark.parametrize("suffix", [".py", ".json"])
def test_round_trip_reproduces_graph_and_compiled_order(tmp_path, suffix):
    g = sample()
    path = g.save(tmp_path / f"sample{suffix}")
    same_graph(g, RenderGraph.load(path))


def test_script_is_falcor_style(tmp_path):
    text = sample().to_script()
    assert "def render_graph_Sample():" in text and "g = RenderGraph('Sample')" in text
    assert "g.addEdge('Pattern.dst', 'Half.src')" in text and "g.markOutput('Half.dst')" in text
    assert "sample = render_graph_Sample()" in text


def test_json_loads_without_running_code_and_names_file_and_field(tmp_path):
    path = tmp_path / "g.json"
    data = sample().to_dict()
    data["passes"][2]["type"] = "Blitt"
    path.write_text(json.dumps(data))
    with pytest.raises(GraphError, match=rf"{path}.passes\[2\].type: unknown pass type 'Blitt' \(did you mean 'Blit'\?\)"):
        RenderGraph.load(path)
    data = sample().to_dict()
    data["passes"][2]["properties"] = {"scal": 2.0}
    path.write_text(json.dumps(data))
    with pytest.raises(GraphError, match=r"passes\[2\].properties: pass Blit: unknown property 'scal' \(did you mean 'scale'\?\)"):
        RenderGraph.load(path)
    data = sample().to_dict()
    del data["passes"][0]["name"]
    path.write_text(json.dumps(data))
    with pytest.raises(GraphError, match=r"passes\[0\]: missing field 'name'"):
        RenderGraph.load(path)
    data = sample().to_dict()
    data["edges"][0] = {"src": "Patern.dst", "dst": "Half.src"}
    path.write_text(json.dumps(data))
    with pytest.raises(GraphError, match=r"edges\[0\]: add_edge.*has no pass 'Patern' \(did you mean 'Pattern'\?\)"):
        RenderGraph.load(path)
    path.write_text('{"name": "X", "passes": [}')
    with pytest.raises(GraphError, match=rf"{path}: not valid JSON at line 1 column"):
        RenderGraph.load(path)
    path.write_text('{"name": "X", "passes": {}}')
    with pytest.raises(GraphError, match=r"g.json.passes: expected list, got dict"):
        RenderGraph.load(path)


def test_script_errors_name_file_and_line(tmp_path):
    path = tmp_path / "bad.py"
    path.write_text("import rayvr as rv\n\nx = 1\nraise ValueError('oops')\n")
    with pytest.raises(GraphError, match=rf"{path}:4: the graph script failed: ValueError: oops"):
        RenderGraph.load(path)
    path.write_text("x = 1\n")
    with pytest.raises(GraphError, match=r"expected one RenderGraph"):
        RenderGraph.load(path)
    with pytest.raises(GraphError, match=r"file not found"):
        RenderGraph.load(tmp_path / "none.json")
    with pytest.raises(GraphError, match=r"unknown suffix '.yaml'; use .py \(script\) or .json"):
        sample().save(tmp_path / "g.yaml")


def test_falcor_style_create_pass(tmp_path):
    path = tmp_path / "falcor.py"
    path.write_text(
        "from rayvr.rendergraph import RenderGraph, createPass\n"
        "def render_graph_Falcor():\n"
        "    g = RenderGraph('Falcor')\n"
        "    Fill = createPass('Clear', {'color': [1, 0, 0, 1]})\n"
        "    g.addPass(Fill, 'Fill')\n"
        "    g.create_pass('Copy', 'Blit', {'format': 'rgba8'})\n"
        "    g.addEdge('Fill.dst', 'Copy.src')\n"
        "    g.markOutput('Copy.dst')\n"
        "    return g\n"
        "Falcor = render_graph_Falcor()\n")
    g = RenderGraph.load(path)
    assert g.get_pass("Fill").color == [1, 0, 0, 1] and type(g.get_pass("Copy")) is Blit
    assert g.plan().order == ["Fill", "Copy"]


def test_registry_registers_and_suggests():
    assert get_pass_class("Blit") is Blit
    assert {"Blit", "Clear", "Checkerboard", "ImageLoader"} <= set(registered_passes())
    with pytest.raises(GraphError, match=r"unknown pass type 'Clera' \(did you mean 'Clear'\?\)"):
        get_pass_class("Clera")
    with pytest.raises(GraphError, match=r"is not a RenderPass subclass"):
        register_pass(int)


def test_dot_and_png(tmp_path):
    dot = sample().to_dot()
    assert '"Pattern" -> "Half" [label="dst -> src"];' in dot
    assert '"Background" -> "Pattern" [style=dashed' in dot
    assert '"Half" -> "out:Half.dst"' in dot
    png = sample().save_picture(tmp_path / "g.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_graph_show(tmp_path, capsys, gpu):
    path = sample().save(tmp_path / "g.json")
    assert cli(["graph", "show", str(path), "--size", "16x8", "--views", "2", "--png", str(tmp_path / "p.png")]) == 0
    out = capsys.readouterr().out
    assert "order: Background -> Pattern -> Half" in out and "Unused: feeds no marked output" in out
    assert (tmp_path / "p.png").is_file()
    assert cli(["graph", "show", str(path), "--dot"]) == 0
    assert capsys.readouterr().out.startswith('digraph "Sample"')
    assert cli(["graph", "show", str(tmp_path / "missing.json")]) == 2
    assert "file not found" in capsys.readouterr().err
    assert cli(["graph", "show", str(path), "--size", "big"]) == 2
    assert "--size big: expected WIDTHxHEIGHT" in capsys.readouterr().err
