"""From a `RenderGraph` to a `Plan`, in named stages (after a frame graph's: Frostbite, Granite).

    validate  names, one source per input, no cycle          -> Topology
    reflect   each pass's pins in topological order (formats flow downstream), edge checks
    prune     passes that feed no marked output, that the scene does not need (skip_reason), or
              whose required input comes from a pruned pass
    order     the kept passes' execution order; every required input connected
    resolve   one logical resource per output/internal pin, with its readers and lifetime
    alias     transients with the same shape and disjoint lifetimes share one GPU object
    (bind     CompiledGraph: allocate, compile the passes, derive barriers and scene binding)

No GPU work happens here, so a plan is cheap to rebuild (the Renderer recompiles when the set of
effects in use changes) and `CompiledGraph` only allocates what the plan says. Each stage is a
function of the previous stages' results and is tested on its own.

Aliasing: a transient resource lives over [first write, last read] in execution order; two
transients with the same kind, format, size and layers whose intervals do not overlap share one
physical texture or buffer. Marked outputs (read after execute) and internal pins (history kept
across frames) never alias.
"""
from __future__ import annotations

import dataclasses
import time

import networkx as nx

from ..errors import GraphError, did_you_mean
from .formats import get_format
from .graph_data import Edge, split_pin
from .render_pass import CompileData, Pin, PinDirection, PinKind, Reflection

DEFAULT_FORMAT = "rgba32f"   # an output pin that declares no format
STAGES = ("validate", "reflect", "prune", "order", "resolve", "alias", "bind")


@dataclasses.dataclass
class Resource:
    """One logical resource: a pass's output or internal pin, with the pins that read it."""

    name: str                   # 'Pass.pin' of the writer
    kind: PinKind
    fmt: str | None             # None for buffers
    size: tuple[int, int]
    layers: int
    byte_size: int              # buffers only
    first: int                  # index in the execution order of the writer
    last: int                   # index of the last reader (== first when nobody reads it)
    readers: list[str] = dataclasses.field(default_factory=list)
    marked: bool = False
    internal: bool = False
    slot: int = -1              # index into Plan.slots

    @property
    def bytes(self) -> int:
        if self.kind is PinKind.BUFFER:
            return self.byte_size
        return self.size[0] * self.size[1] * self.layers * get_format(self.fmt).bytes_per_texel

    @property
    def alias_key(self) -> tuple:
        return (self.kind, self.fmt, self.size, self.layers, self.byte_size)

    @property
    def transient(self) -> bool:
        return not (self.marked or self.internal)


@dataclasses.dataclass
class Slot:
    """One physical GPU object and the resources that share it over the frame."""

    key: tuple
    bytes: int
    resources: list[str]
    last: int


@dataclasses.dataclass
class Topology:
    """What `validate` established: the graph's passes and edges, one source per input, a
    topological order of every pass."""

    name: str
    passes: dict
    edges: list[Edge]
    into: dict[tuple[str, str], Edge]          # (pass, input pin) -> its one data edge
    edges_into: dict[str, list[Edge]]          # pass -> data edges into it
    order: list[str]                           # every pass, topologically, ties by insertion order
    size: tuple[int, int]
    views: int
    outputs: list[str]


@dataclasses.dataclass
class Reflected:
    """What `reflect` established: each pass's pins, compile data and output shapes."""

    reflections: dict[str, Reflection]
    compile_data: dict[str, CompileData]
    shapes: dict[tuple[str, str], tuple]       # (pass, pin) -> (format, size, layers)


@dataclasses.dataclass
class Pruning:
    """What `prune` decided: why each dropped pass does not run; which marked outputs remain."""

    pruned: dict[str, str]
    outputs: list[str]                         # marked outputs that are produced
    unavailable: dict[str, str]                # marked outputs of pruned passes -> why


@dataclasses.dataclass
class Plan:
    """Everything compile decided, before any GPU allocation."""

    graph_name: str
    size: tuple[int, int]
    views: int
    order: list[str]                                  # kept passes, execution order
    pruned: dict[str, str]                            # pass -> why it does not run
    reflections: dict[str, Reflection]
    compile_data: dict[str, CompileData]              # per kept pass (input_formats filled)
    resources: dict[str, Resource]                    # by 'Pass.pin' of the writer
    bindings: dict[str, dict[str, str | None]]        # pass -> pin -> resource name (None: absent)
    slots: list[Slot]
    outputs: list[str]                                # marked outputs that are produced
    unavailable: dict[str, str]                       # marked outputs of pruned passes -> why
    stage_ms: dict[str, float] = dataclasses.field(default_factory=dict)   # CPU ms per stage

    @property
    def total_bytes(self) -> int:
        return sum(s.bytes for s in self.slots)

    @property
    def unaliased_bytes(self) -> int:
        return sum(r.bytes for r in self.resources.values())

    @property
    def wants_jitter(self) -> bool:
        """A kept pass asked for sub-pixel camera jitter (Reflection.request_jitter)."""
        return any(self.reflections[p].jitter for p in self.order)


# -- validate ------------------------------------------------------------------------------------
def validate(graph, size=(64, 64), views: int = 1) -> Topology:
    """Names, sizes, marked outputs, no cycle, at most one source per input."""
    name = graph.name
    passes = graph.passes
    edges: list[Edge] = graph.edges
    try:
        size, views = (int(size[0]), int(size[1])), int(views)
    except (TypeError, ValueError, IndexError, OverflowError):
        raise GraphError(f"graph '{name}': compile size {size!r} x {views!r} views: give size=(width, height) "
                         f"and views as whole numbers, e.g. size=(256, 256), views=2") from None
    if size[0] < 1 or size[1] < 1 or views < 1:
        raise GraphError(f"graph '{name}': compile size {size} x {views} views must be positive")
    if not passes:
        raise GraphError(f"graph '{name}' is empty: add passes with add_pass(pass, 'Name')")
    if not graph.outputs:
        raise GraphError(f"graph '{name}' has no marked output: mark one with mark_output('Pass.pin')")
    index = {p: i for i, p in enumerate(passes)}
    g = nx.DiGraph()
    g.add_nodes_from(passes)
    g.add_edges_from((e.src_pass, e.dst_pass) for e in edges)
    try:
        cycle = nx.find_cycle(g)
    except nx.NetworkXNoCycle:
        cycle = None
    if cycle:
        chain = " -> ".join([u for u, _ in cycle] + [cycle[0][0]])
        raise GraphError(f"graph '{name}' has a cycle {chain}: remove one of these edges with remove_edge() "
                         f"(history belongs in an internal pin)")
    order = list(nx.lexicographical_topological_sort(g, key=index.__getitem__))
    into: dict[tuple[str, str], Edge] = {}
    for e in edges:
        if not e.is_data:
            continue
        other = into.get((e.dst_pass, e.dst_pin))
        if other is not None:
            raise GraphError(f"input '{e.dst}' has two sources '{other.src}' and '{e.src}': "
                             f"remove one with remove_edge('{e.src}', '{e.dst}')")
        into[(e.dst_pass, e.dst_pin)] = e
    edges_into: dict[str, list[Edge]] = {p: [] for p in passes}
    for e in into.values():
        edges_into[e.dst_pass].append(e)
    return Topology(name, passes, edges, into, edges_into, order, size, int(views), graph.outputs)


# -- reflect -------------------------------------------------------------------------------------
def reflect(topo: Topology, scene=None, caps=None) -> Reflected:
    """Each pass's reflection in topological order, so each sees its sources' formats; every
    edge's pins exist and fit, every marked output exists."""
    reflections: dict[str, Reflection] = {}
    cds: dict[str, CompileData] = {}
    shapes: dict[tuple[str, str], tuple] = {}
    for p in topo.order:
        rp = topo.passes[p]
        type_name = type(rp).__name__
        input_formats = {}
        for e in topo.edges_into[p]:
            _check_pin(reflections[e.src_pass], e.src_pass, type(topo.passes[e.src_pass]).__name__, e.src_pin,
                       PinDirection.OUTPUT, f"edge {e}")
            input_formats[e.dst_pin] = shapes[(e.src_pass, e.src_pin)][0]
        cd = CompileData(size=topo.size, views=topo.views, scene=scene, caps=caps, input_formats=input_formats)
        refl = rp.reflect(cd)
        if not isinstance(refl, Reflection):
            raise GraphError(f"pass '{p}' ({type_name}): reflect() returned {type(refl).__name__}, "
                             f"not a Reflection; return the Reflection it built")
        reflections[p], cds[p] = refl, cd
        for pin in refl.pins.values():
            if pin.direction is not PinDirection.INPUT:
                shapes[(p, pin.name)] = _output_shape(pin, topo.size, topo.views)
        for e in topo.edges_into[p]:
            inp = _check_pin(refl, p, type_name, e.dst_pin, PinDirection.INPUT, f"edge {e}")
            _check_compatible(e, reflections[e.src_pass].pins[e.src_pin], inp,
                              shapes[(e.src_pass, e.src_pin)], topo.size)
    for ref in topo.outputs:
        p, pin = split_pin(ref)
        _check_pin(reflections[p], p, type(topo.passes[p]).__name__, pin, PinDirection.OUTPUT,
                   f"mark_output('{ref}')")
    return Reflected(reflections, cds, shapes)


# -- prune ---------------------------------------------------------------------------------------
def prune(topo: Topology, refl: Reflected) -> Pruning:
    """Drop the passes that feed no marked output (edges into inputs their readers leave unused
    keep nothing alive), that the scene does not need (skip_reason), or whose required input
    comes from a pruned pass; repeat the reachability after the skips."""
    reflections = refl.reflections
    unused = {(e.dst_pass, e.dst_pin): reflections[e.dst_pass].pins[e.dst_pin].unused_reason
              for e in topo.into.values() if reflections[e.dst_pass].pins[e.dst_pin].unused_reason}
    live = nx.DiGraph()
    live.add_nodes_from(topo.passes)
    live.add_edges_from((e.src_pass, e.dst_pass) for e in topo.edges
                        if not (e.is_data and (e.dst_pass, e.dst_pin) in unused))
    reach = _reaching(live, {split_pin(r)[0] for r in topo.outputs})
    pruned = {p: _unreached_reason(p, topo.edges, unused, {}) for p in topo.order if p not in reach}
    for p in topo.order:
        if p in pruned:
            continue
        reason = topo.passes[p].skip_reason(refl.compile_data[p])
        if reason:
            pruned[p] = str(reason)
            continue
        for pin in reflections[p].inputs():
            e = topo.into.get((p, pin.name))
            if e is not None and e.src_pass in pruned and not pin.is_optional:
                pruned[p] = (f"required input '{pin.name}' comes from '{e.src_pass}', which was pruned "
                             f"({e.src_pass}: {pruned[e.src_pass]})")
                break
    kept_outputs = [r for r in topo.outputs if split_pin(r)[0] not in pruned]
    reach = _reaching(live.subgraph([p for p in topo.order if p not in pruned]),
                      {split_pin(r)[0] for r in kept_outputs})
    for p in topo.order:
        if p not in pruned and p not in reach:
            pruned[p] = _unreached_reason(p, topo.edges, unused, pruned)
    unavailable = {r: pruned[split_pin(r)[0]] for r in topo.outputs if r not in kept_outputs}
    return Pruning(pruned, kept_outputs, unavailable)


def _reaching(g: nx.DiGraph, targets: set) -> set:
    """`targets` and every node with a path to one of them."""
    reach = set(targets)
    for p in targets:
        reach |= nx.ancestors(g, p)
    return reach


# -- order ---------------------------------------------------------------------------------------
def order(topo: Topology, refl: Reflected, pruning: Pruning) -> list[str]:
    """The kept passes in topological order; each required input must be connected."""
    kept = [p for p in topo.order if p not in pruning.pruned]
    for p in kept:
        for pin in refl.reflections[p].inputs():
            if not pin.is_optional and (p, pin.name) not in topo.into:
                srcs = [f"{q}.{o.name}" for q in kept if q != p for o in refl.reflections[q].outputs()]
                raise GraphError(f"pass '{p}' ({type(topo.passes[p]).__name__}): required input '{pin.name}' is not "
                                 f"connected; add_edge('<Pass>.<output>', '{p}.{pin.name}')"
                                 f"{' (outputs: ' + ', '.join(srcs[:8]) + ')' if srcs else ''}")
    return kept


# -- resolve -------------------------------------------------------------------------------------
def resolve(topo: Topology, refl: Reflected, pruning: Pruning,
            kept: list[str]) -> tuple[dict[str, Resource], dict[str, dict[str, str | None]]]:
    """One Resource per output and internal pin of a kept pass (lifetime: writer to last reader),
    and each pass's pin -> resource binding (None: an input from a pruned pass or left unused)."""
    resources: dict[str, Resource] = {}
    bindings: dict[str, dict[str, str | None]] = {}
    marked = set(pruning.outputs)
    for i, p in enumerate(kept):
        bind: dict[str, str | None] = {}
        for pin in refl.reflections[p].pins.values():
            ref = f"{p}.{pin.name}"
            if pin.direction is PinDirection.INPUT:
                e = topo.into.get((p, pin.name))
                if e is None or e.src_pass in pruning.pruned or pin.unused_reason:
                    bind[pin.name] = None
                    continue
                res = resources[e.src]
                res.last = max(res.last, i)
                res.readers.append(ref)
                bind[pin.name] = res.name
            else:
                fmt, rsize, layers = refl.shapes[(p, pin.name)]
                resources[ref] = Resource(ref, pin.kind, fmt, rsize, layers, pin.byte_size, i, i,
                                          marked=ref in marked,
                                          internal=pin.direction is PinDirection.INTERNAL)
                bind[pin.name] = ref
        bindings[p] = bind
    return resources, bindings


# -- alias ---------------------------------------------------------------------------------------
def alias(resources: dict[str, Resource]) -> list[Slot]:
    """Greedy interval sharing: each transient takes the free matching slot released earliest.
    Sets each resource's `slot`."""
    slots: list[Slot] = []
    for r in sorted(resources.values(), key=lambda r: (r.first, r.name)):
        choice = None
        if r.transient:
            free = [s for s in slots if s.key == r.alias_key and s.last < r.first]
            if free:
                choice = min(free, key=lambda s: s.last)
        if choice is None:
            choice = Slot(r.alias_key, r.bytes, [], r.last if r.transient else 1 << 62)
            slots.append(choice)
        choice.resources.append(r.name)
        choice.last = r.last if r.transient else choice.last
        r.slot = slots.index(choice)
    return slots


# -- the stages together ---------------------------------------------------------------------------
def plan_graph(graph, scene=None, size=(64, 64), views: int = 1, caps=None) -> Plan:
    """Run validate, reflect, prune, order, resolve and alias; raises GraphError naming the pass
    and pin and the fix."""
    ms: dict[str, float] = {}
    t = time.perf_counter()

    def lap(stage: str) -> None:
        nonlocal t
        now = time.perf_counter()
        ms[stage] = (now - t) * 1e3
        t = now

    topo = validate(graph, size, views)
    lap("validate")
    refl = reflect(topo, scene, caps)
    lap("reflect")
    pruning = prune(topo, refl)
    lap("prune")
    kept = order(topo, refl, pruning)
    lap("order")
    resources, bindings = resolve(topo, refl, pruning, kept)
    lap("resolve")
    slots = alias(resources)
    lap("alias")
    # compile() sees only the inputs that will be bound (not those from pruned passes).
    compile_data = {p: dataclasses.replace(refl.compile_data[p], input_formats={
        pin: f for pin, f in refl.compile_data[p].input_formats.items() if bindings[p].get(pin) is not None})
        for p in kept}
    return Plan(topo.name, topo.size, topo.views, kept, pruning.pruned, refl.reflections, compile_data,
                resources, bindings, slots, pruning.outputs, pruning.unavailable, ms)


# -- checks shared by the stages -------------------------------------------------------------------
def _check_pin(refl: Reflection, pass_name: str, type_name: str, pin: str, want: PinDirection,
               where: str) -> Pin:
    """The pin `pin` of a pass, which must have direction `want`; GraphError naming it otherwise."""
    wanted = [p.name for p in refl.pins_of(want)]
    p = refl.pins.get(pin)
    if p is None:
        raise GraphError(f"{where}: pass '{pass_name}' ({type_name}) has no {want.value} '{pin}'"
                         f"{did_you_mean(pin, wanted)}; its {want.value}s: {', '.join(wanted) or '(none)'}")
    if p.direction is not want:
        raise GraphError(f"{where}: '{pass_name}.{pin}' is an {p.direction.value} pin, not an "
                         f"{want.value}; use one of {pass_name}'s {want.value}s: {', '.join(wanted) or '(none)'}")
    return p


def _output_shape(pin: Pin, size, views) -> tuple:
    fmt = None if pin.kind is PinKind.BUFFER else (pin.fmt or DEFAULT_FORMAT)
    return fmt, pin.resolved_size(size), (pin.layers or views)


def _unreached_reason(p: str, edges, unused: dict, pruned: dict) -> str:
    """Why pass `p` reaches no marked output: the pruned passes and the unused inputs it feeds."""
    out = [e for e in edges if e.src_pass == p]
    dead = sorted({e.dst_pass for e in out if e.dst_pass in pruned})
    idle = [f"{e.dst} ({unused[(e.dst_pass, e.dst_pin)]})" for e in out
            if e.is_data and (e.dst_pass, e.dst_pin) in unused and e.dst_pass not in pruned]
    parts = ([f"pruned passes ({', '.join(dead)})"] if dead else []) + \
        ([f"inputs their passes leave unused: {', '.join(idle)}"] if idle else [])
    return f"feeds only {' and '.join(parts)}" if parts else "feeds no marked output"


def _check_compatible(e: Edge, out: Pin, inp: Pin, shape: tuple, size) -> None:
    fmt, rsize, layers = shape
    if out.kind is not inp.kind:
        raise GraphError(f"edge {e}: '{e.src}' is a {out.kind.value} but '{e.dst}' takes a {inp.kind.value}; "
                         f"connect a {inp.kind.value} output")
    if inp.kind is PinKind.BUFFER:
        if inp.byte_size and out.byte_size < inp.byte_size:
            raise GraphError(f"edge {e}: '{e.src}' has {out.byte_size} bytes but '{e.dst}' needs "
                             f"{inp.byte_size}; enlarge the source buffer")
        return
    if inp.fmt and inp.fmt != fmt:
        raise GraphError(f"edge {e}: format conflict, '{e.src}' is {fmt} but '{e.dst}' needs {inp.fmt}; "
                         f"set the source's format to {inp.fmt} or insert a Blit({{'format': '{inp.fmt}'}})")
    if inp.size_rule != "output":   # an input that states a size (fixed or scaled) must get it
        want = inp.resolved_size(size)
        if want != rsize:
            raise GraphError(f"edge {e}: size conflict, '{e.src}' is {rsize[0]}x{rsize[1]} but '{e.dst}' "
                             f"needs {want[0]}x{want[1]}; insert a Blit to rescale")
    if inp.layers is not None and inp.layers != layers:
        raise GraphError(f"edge {e}: view-count conflict, '{e.src}' has {layers} layers but '{e.dst}' "
                         f"needs {inp.layers}; make the source declare views({inp.layers})")
