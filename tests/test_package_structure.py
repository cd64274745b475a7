"""The package's shape: no import cycle among rayvr's modules at module level, and every pass
folder's passes reachable as rayvr.passes.<Name> without an edit elsewhere."""
import ast
import importlib
import pkgutil
from pathlib import Path

import networkx as nx

import rayvr

ROOT = Path(rayvr.__file__).resolve().parent


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def module_level_imports(path: Path, name: str, modules) -> set[str]:
    """The rayvr modules `path` imports at module level (not inside functions or classes):
    `from pkg import sub` counts as importing the submodule when `sub` is one."""
    tree = ast.parse(path.read_text())
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = set()
    for node in tree.body:
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.startswith("rayvr")}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("rayvr"):
                continue
            subs = [f"{target}.{a.name}" for a in node.names if f"{target}.{a.name}" in modules]
            out |= set(subs) if len(subs) == len(node.names) else {target, *subs}
    return out


def test_no_module_level_import_cycle():
    modules = {module_name(p): p for p in ROOT.rglob("*.py")}
    g = nx.DiGraph()
    for name, path in modules.items():
        for target in module_level_imports(path, name, modules):
            # 'from pkg import sub' names a submodule or a symbol: count the deepest existing module
            while target not in modules and "." in target:
                target = target.rpartition(".")[0]
            if target in modules and target != name:
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
