"""Save and load graphs: a Falcor-style Python script (code: loading runs it) and JSON (data:
loading builds passes through the registry and runs no code)."""
from __future__ import annotations

import json
import runpy
import sys
import traceback
from pathlib import Path

from ..errors import GraphError, RayvrError
from ..fileio import write_text
from .graph_data import GraphData
from .registry import get_pass_class

JSON_FORMAT = "rayvr.rendergraph"
JSON_VERSION = 1


def graph_to_dict(graph) -> dict:
    return {
        "format": JSON_FORMAT,
        "version": JSON_VERSION,
        "name": graph.name,
        "passes": [{"name": n, "type": type(p).__name__, "properties": p.get_properties()}
                   for n, p in graph.passes.items()],
        "edges": [{"src": e.src, "dst": e.dst} for e in graph.edges],
        "outputs": graph.outputs,
    }


def _names(kind) -> str:
    return kind.__name__ if isinstance(kind, type) else "/".join(k.__name__ for k in kind)


def _field(obj: dict, key: str, kind, where: str, default=None):
    if key not in obj:
        if default is not None:
            return default
        raise GraphError(f"{where}: missing field '{key}'; add it ({_names(kind)}), or write the file "
                         f"with RenderGraph.save('g.json') to see the format")
    value = obj[key]
    if not isinstance(value, kind):
        raise GraphError(f"{where}.{key}: expected {_names(kind)}, got {type(value).__name__} {value!r}")
    return value


def graph_from_dict(data: dict, graph_type: type[GraphData], where: str = "graph"):
    """A `graph_type` built from `graph_to_dict()` output; errors name `where` and the field."""
    if not isinstance(data, dict):
        raise GraphError(f"{where}: expected a JSON object with 'name', 'passes', 'edges', 'outputs'")
    if data.get("format", JSON_FORMAT) != JSON_FORMAT:
        raise GraphError(f"{where}.format: {data['format']!r} is not a rayvr graph (expected {JSON_FORMAT!r})")
    version = data.get("version", JSON_VERSION)
    if version != JSON_VERSION:
        raise GraphError(f"{where}.version: {version!r} is not supported (this rayvr reads {JSON_VERSION})")
    g = graph_type(_field(data, "name", str, where))
    for i, entry in enumerate(_field(data, "passes", list, where)):
        at = f"{where}.passes[{i}]"
        if not isinstance(entry, dict):
            raise GraphError(f"{at}: expected an object with 'name', 'type', 'properties'")
        cls = get_pass_class(_field(entry, "type", str, at), where=f"{at}.type")
        props = _field(entry, "properties", dict, at, default={})
        try:
            render_pass = cls(props)
        except RayvrError as exc:
            raise GraphError(f"{at}.properties: {exc}") from exc
        try:
            g.add_pass(render_pass, _field(entry, "name", str, at))
        except GraphError as exc:
            raise GraphError(f"{at}.name: {exc}") from exc
    for i, entry in enumerate(_field(data, "edges", list, where, default=[])):
        at = f"{where}.edges[{i}]"
        if isinstance(entry, (list, tuple)) and len(entry) == 2:
            src, dst = entry
        elif isinstance(entry, dict):
            src, dst = _field(entry, "src", str, at), _field(entry, "dst", str, at)
        else:
            raise GraphError(f"{at}: expected {{'src': 'A.out', 'dst': 'B.in'}}")
        try:
            g.add_edge(src, dst)
        except GraphError as exc:
            raise GraphError(f"{at}: {exc}") from exc
    for i, ref in enumerate(_field(data, "outputs", list, where, default=[])):
        try:
            g.mark_output(ref)
        except GraphError as exc:
            raise GraphError(f"{where}.outputs[{i}]: {exc}") from exc
    return g


def _pass_expr(cls: type) -> tuple[str, str | None]:
    """How the script names a pass class: rv.<package>.X when a package of rayvr exports it
    (rv.passes.X for rayvr's own passes), else an import from its package or module."""
    parts = cls.__module__.split(".")
    top = ".".join(parts[:2])   # rayvr.<package>
    if len(parts) > 2 and parts[0] == "rayvr" and getattr(sys.modules.get(top), cls.__name__, None) is cls:
        return f"rv.{parts[1]}.{cls.__name__}", None
    package = cls.__module__.rpartition(".")[0]
    module = package if getattr(sys.modules.get(package), cls.__name__, None) is cls else cls.__module__
    return cls.__name__, f"from {module} import {cls.__name__}"


def graph_to_script(graph) -> str:
    name = graph.name
    var = name.lower() if name.lower() not in ("rv", "rendergraph") else f"{name.lower()}_graph"
    imports, body = ["import rayvr as rv", "from rayvr.rendergraph.graph import RenderGraph"], []
    for pname, p in graph.passes.items():
        expr, imp = _pass_expr(type(p))
        if imp and imp not in imports:
            imports.append(imp)
        body.append(f"    g.addPass({expr}({p.get_properties()!r}), {pname!r})")
    body += [f"    g.addEdge({e.src!r}, {e.dst!r})" for e in graph.edges]
    body += [f"    g.markOutput({o!r})" for o in graph.outputs]
    return "\n".join([
        f"# rayvr render graph '{name}'. Load with rayvr.RenderGraph.load(path): this script runs.",
        *imports, "", "",
        f"def render_graph_{name}():",
        f"    g = RenderGraph({name!r})",
        *body,
        "    return g", "", "",
        f"{var} = render_graph_{name}()", ""])


def save_graph(graph, path) -> Path:
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".py":
        text = graph_to_script(graph)
    elif suffix == ".json":
        text = json.dumps(graph_to_dict(graph), indent=2) + "\n"
    else:
        raise GraphError(f"save('{path}'): unknown suffix '{path.suffix}'; use .py (script) or .json")
    write_text(path, text)
    return path


def load_graph(path, graph_type: type[GraphData]):
    """A `graph_type` from a .json file (not executed), or the one a .py script (executed) makes."""
    path = Path(path)
    if not path.is_file():
        raise GraphError(f"load('{path}'): file not found; give a saved graph (.py or .json)")
    suffix = path.suffix.lower()
    if suffix == ".json":
        try:
            data = json.loads(path.read_text())
        except json.JSONDecodeError as exc:
            raise GraphError(f"{path}: not valid JSON at line {exc.lineno} column {exc.colno}: {exc.msg}") from None
        return graph_from_dict(data, graph_type, where=str(path))
    if suffix != ".py":
        raise GraphError(f"load('{path}'): unknown suffix '{path.suffix}'; use .py (script) or .json")
    try:
        namespace = runpy.run_path(str(path), run_name="__rayvr_graph__")
    except RayvrError as exc:
        raise type(exc)(f"{path}: {exc}") from exc
    except Exception as exc:
        lines = [f.lineno for f in traceback.extract_tb(sys.exc_info()[2]) if Path(f.filename) == path]
        at = f":{lines[-1]}" if lines else ""
        raise GraphError(f"{path}{at}: the graph script failed: {type(exc).__name__}: {exc}") from exc
    graphs = list({id(v): v for v in namespace.values() if isinstance(v, graph_type)}.values())
    if len(graphs) == 1:
        return graphs[0]
    makers = [v for k, v in namespace.items() if k.startswith("render_graph_") and callable(v)]
    if len(makers) == 1:
        graph = makers[0]()
        if isinstance(graph, graph_type):
            return graph
    found = ", ".join(g.name for g in graphs) or "none"
    raise GraphError(f"{path}: expected one RenderGraph (or one render_graph_<Name>() function) in the "
                     f"script, found graphs: {found}")
