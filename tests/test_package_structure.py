"""The package's shape: no import cycle among rayvr's modules at module level, none inside a
package even through imports in functions, no lower floor naming an upper one, and every pass
folder's passes reachable as rayvr.passes.<Name> without an edit elsewhere."""
import ast
import importlib
import os
import pkgutil
import re
from pathlib import Path

import networkx as nx
import pytest

import rayvr

ROOT = Path(rayvr.__file__).resolve().parent


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imported(node, package: str, modules) -> set[str]:
    """What an import statement in `package` names: `from pkg import sub` counts as importing
    the submodule when `sub` is one (and else the package)."""
    if isinstance(node, ast.Import):
        return {a.name for a in node.names}
    if node.level:
        base = package.split(".")
        base = base[:len(base) - (node.level - 1)]
        target = ".".join(base + ([node.module] if node.module else []))
    else:
        target = node.module or ""
    subs = {f"{target}.{a.name}" for a in node.names if f"{target}.{a.name}" in modules}
    return subs if len(subs) == len(node.names) else {target, *subs}


def deepest_module(target: str, modules) -> str | None:
    """'from pkg import sub' names a submodule or a symbol: the deepest existing module."""
    while target not in modules and "." in target:
        target = target.rpartition(".")[0]
    return target if target in modules else None


def package_of(path: Path, name: str) -> str:
    return name if path.name == "__init__.py" else name.rpartition(".")[0]


def module_level_imports(path: Path, name: str, modules) -> set[str]:
    """The rayvr modules `path` imports at module level (not inside functions or classes)."""
    tree = ast.parse(path.read_text())
    package = package_of(path, name)
    return {t for node in tree.body if isinstance(node, (ast.Import, ast.ImportFrom))
            for t in imported(node, package, modules) if t.startswith("rayvr")}


def test_no_module_level_import_cycle():
    modules = {module_name(p): p for p in ROOT.rglob("*.py")}
    g = nx.DiGraph()
    for name, path in modules.items():
        for target in module_level_imports(path, name, modules):
            target = deepest_module(target, modules)
            if target and target != name:
                g.add_edge(name, target)
    cycles = list(nx.simple_cycles(g))
    assert not cycles, cycles[:5]


def test_every_pass_folder_is_discovered():
    import rayvr.passes as passes
    from rayvr.rendergraph.registry import registered_passes

    folders = [m.name for m in pkgutil.iter_modules(passes.__path__) if m.ispkg]
    registered = registered_passes()
    for folder in folders:
        module = importlib.import_module(f"rayvr.passes.{folder}")
        for name in module.__all__:
            value = getattr(module, name)
            if isinstance(value, type) and name in registered:
                assert getattr(passes, name) is value and registered[name] is value
    assert {"GBufferRaster", "PathTracer", "ToneMapper", "Blit"} <= set(passes.__all__)


# The house's floors, lowest first: a module may import (at module level or inside a function)
# and name by string (importlib, "module:function" tables) only modules of its own floor or
# lower ones. The package face rayvr/__init__.py stands outside the floors: its lazy table names
# every room, and any room may import it.
LAYERS = (
    ("errors",),
    ("fileio", "images"),
    ("gpu",),
    ("materials",),   # its texture slots come from the GPU records' table
    ("rendergraph", "scene"),
    ("xr",),
    ("passes",),
    ("graphs", "graph_options"),
    ("renderer",),
    ("check", "study"),
    ("tune",),
    ("cluster", "viewer"),
    ("cli", "__main__"),
)
FLOOR = {room: i for i, rooms in enumerate(LAYERS) for room in rooms}
# Packages whose modules may not import each other in a circle, even inside functions.
CIRCLE_FREE = ("rendergraph", "study", "tune", "passes", "gpu", "scene", "xr", "cluster", "viewer", "cli", "materials")
MODULE_PATH = re.compile(r"rayvr(\.[A-Za-z_]\w*)+(:\w+)?")


def room(module: str) -> str:
    """The top-level room of a rayvr module: 'rayvr.passes.svgf.svgf' -> 'passes'."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def all_imports(path: Path, name: str, modules) -> set[str]:
    """The rayvr modules `path` imports anywhere (module level, functions, classes), and those it
    names in code by a string such as "rayvr.passes" or "rayvr.passes.gbuffer.channels:glsl_source"
    (docstrings aside)."""
    tree = ast.parse(path.read_text())
    package = package_of(path, name)
    docstrings = {id(n.body[0].value) for n in ast.walk(tree)
                  if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
                  and n.body and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
    targets, named = set(), set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            targets |= imported(node, package, modules)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
            if MODULE_PATH.fullmatch(node.value):
                named.add(deepest_module(node.value.partition(":")[0], modules))
    found = {deepest_module(t, modules) for t in targets if t.startswith("rayvr")}
    # a string naming the module's own package (a label such as "rayvr.cluster") imports nothing
    found |= {t for t in named if t and not name.startswith(f"{t}.")}
    return {t for t in found if t and t != name}


def import_graph() -> tuple[nx.DiGraph, dict]:
    modules = {module_name(p): p for p in ROOT.rglob("*.py")}
    g = nx.DiGraph()
    for name, path in modules.items():
        g.add_node(name)
        for target in all_imports(path, name, modules):
            g.add_edge(name, target)
    return g, modules


@pytest.mark.parametrize("package", CIRCLE_FREE)
def test_no_import_circle_in_a_package_even_inside_functions(package):
    g, _ = import_graph()
    inside = g.subgraph([m for m in g if room(m) == package])
    cycles = list(nx.simple_cycles(inside))
    assert not cycles, cycles[:5]


def test_no_lower_floor_names_an_upper_one():
    g, modules = import_graph()
    assert set(FLOOR) == {room(m) for m in modules if m != "rayvr"}, "give every room a floor in LAYERS"
    upward = sorted(f"{a} -> {b}" for a, b in g.edges
                    if room(a) and room(b) and FLOOR[room(b)] > FLOOR[room(a)])
    assert not upward, upward


def test_the_checks_see_imports_inside_functions_and_module_strings(tmp_path):
    """The circle and floor checks read what a function imports and a string that names a module."""
    modules = {"rayvr.passes": None, "rayvr.passes.gbuffer.channels": None, "rayvr.rendergraph.graph": None,
               "rayvr.rendergraph.compiler": None}
    path = tmp_path / "compiler.py"
    path.write_text('"""rayvr.passes is named in a docstring only."""\n'
                    "def plan():\n    from .graph import RenderGraph\n"
                    'SOURCES = {"x.glsl": "rayvr.passes.gbuffer.channels:glsl_source"}\n'
                    'MESSAGE = "see rayvr.passes.PathTracer for one"\n')
    assert all_imports(path, "rayvr.rendergraph.compiler", modules) == {"rayvr.rendergraph.graph",
                                                                        "rayvr.passes.gbuffer.channels"}


def test_a_pass_folder_registers_itself_and_a_json_graph_finds_it(tmp_path):
    """The registry names no pass package: rayvr's face adds rayvr.passes as a pass source, and a
    fresh interpreter loads a JSON graph of built-in passes without importing them first."""
    import subprocess
    import sys

    import rayvr as rv
    from rayvr.passes.basic import Blit, Clear

    g = rv.RenderGraph("Sample")
    g.add_pass(Clear(), "Fill")
    g.add_pass(Blit(), "Copy")
    g.add_edge("Fill.dst", "Copy.src")
    g.mark_output("Copy.dst")
    path = g.save(tmp_path / "g.json")
    code = ("import sys, rayvr as rv; g = rv.RenderGraph.load(sys.argv[1]); "
            "assert 'rayvr.passes' in sys.modules; print(type(g.get_pass('Copy')).__name__, g.plan().order)")
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT.parent),
                                                                                          os.environ.get("PYTHONPATH")]))})
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["Blit", "['Fill',", "'Copy']"]
