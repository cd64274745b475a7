"""Pictures of a graph: DOT text, and PNG/SVG/PDF through graphviz `dot` or matplotlib."""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

from ..errors import GraphError
from ..fileio import atomic_write


def _q(*lines: str) -> str:
    """A quoted DOT string; several arguments become lines."""
    return '"' + "\\n".join(str(s).replace("\\", "\\\\").replace('"', '\\"') for s in lines) + '"'


def graph_to_dot(graph) -> str:
    """Passes as boxes (name and type), data edges labelled 'out -> in', ordering edges dashed,
    marked outputs as bold arrows into ellipses."""
    lines = [f"digraph {_q(graph.name)} {{", "  rankdir=LR;",
             '  node [shape=box, style="rounded,filled", fillcolor="#eef3fb", fontname="Helvetica"];',
             '  edge [fontname="Helvetica", fontsize=10];']
    for name, p in graph.passes.items():
        lines.append(f"  {_q(name)} [label={_q(name, type(p).__name__)}];")
    for e in graph.edges:
        attrs = f"label={_q(e.src_pin + ' -> ' + e.dst_pin)}" if e.is_data else 'style=dashed, label="order"'
        lines.append(f"  {_q(e.src_pass)} -> {_q(e.dst_pass)} [{attrs}];")
    for ref in graph.outputs:
        node = "out:" + ref
        lines.append(f'  {_q(node)} [label={_q(ref)}, shape=ellipse, fillcolor="#fff2cc"];')
        lines.append(f"  {_q(ref.split('.')[0])} -> {_q(node)} [penwidth=2];")
    lines.append("}")
    return "\n".join(lines) + "\n"


def picture_format(path) -> str:
    """'png', 'svg' or 'pdf' from the suffix of `path`; GraphError for any other."""
    fmt = Path(path).suffix.lower().lstrip(".")
    if fmt not in ("png", "svg", "pdf"):
        raise GraphError(f"save_picture('{path}'): use a .png, .svg or .pdf file name")
    return fmt


def save_picture(graph, path) -> Path:
    """Draw `graph` to a .png, .svg or .pdf file: graphviz `dot` when on PATH, else matplotlib."""
    path = Path(path)
    fmt = picture_format(path)
    dot = shutil.which("dot")
    if dot:
        dot_text = graph_to_dot(graph).encode()

        def run_dot(tmp: Path) -> None:
            done = subprocess.run([dot, f"-T{fmt}", "-o", str(tmp)], input=dot_text, capture_output=True)
            if done.returncode:
                raise GraphError(f"save_picture('{path}'): graphviz dot failed: "
                                 f"{done.stderr.decode(errors='replace').strip() or done.returncode}")

        return atomic_write(path, run_dot)
    return _draw_matplotlib(graph, path)


def _draw_matplotlib(graph, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import networkx as nx

    g = nx.MultiDiGraph()
    g.add_nodes_from(graph.passes)
    for e in graph.edges:
        g.add_edge(e.src_pass, e.dst_pass)
    # Layered left-to-right layout by longest path from a source (falls back for cycles).
    try:
        for layer, nodes in enumerate(nx.topological_generations(g)):
            for n in nodes:
                g.nodes[n]["layer"] = layer
        pos = nx.multipartite_layout(g, subset_key="layer")
    except nx.NetworkXUnfeasible:
        pos = nx.spring_layout(g, seed=1)
    fig, ax = plt.subplots(figsize=(max(4, 2.2 * len(graph.passes)), 3 + 0.4 * len(graph.passes)))
    labels = {n: f"{n}\n{type(p).__name__}" + "".join(f"\n[{o.split('.')[1]}]" for o in graph.outputs
                                                      if o.split('.')[0] == n)
              for n, p in graph.passes.items()}
    nx.draw_networkx_nodes(g, pos, ax=ax, node_shape="s", node_size=2600, node_color="#eef3fb",
                           edgecolors="#556")
    nx.draw_networkx_labels(g, pos, labels, ax=ax, font_size=8)
    data = [(e.src_pass, e.dst_pass) for e in graph.edges if e.is_data]
    order = [(e.src_pass, e.dst_pass) for e in graph.edges if not e.is_data]
    nx.draw_networkx_edges(g, pos, edgelist=data, ax=ax, arrows=True, node_size=2600)
    nx.draw_networkx_edges(g, pos, edgelist=order, ax=ax, arrows=True, style="dashed", node_size=2600)
    edge_labels: dict = {}
    for e in graph.edges:
        if e.is_data:
            key = (e.src_pass, e.dst_pass)
            edge_labels[key] = "\n".join(filter(None, [edge_labels.get(key), f"{e.src_pin}->{e.dst_pin}"]))
    nx.draw_networkx_edge_labels(nx.DiGraph(list(edge_labels)), pos, edge_labels=edge_labels, ax=ax,
                                 font_size=7)
    ax.margins(0.15)
    ax.set_title(f"render graph '{graph.name}'")
    ax.axis("off")
    try:
        return atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=100, bbox_inches="tight"))
    finally:
        plt.close(fig)
