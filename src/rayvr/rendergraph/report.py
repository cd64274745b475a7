"""The compile report: what runs in which order, what was pruned and why, memory and aliasing."""
from __future__ import annotations

import dataclasses


def human_bytes(n: int) -> str:
    """`n` bytes in B, KiB, MiB or GiB, e.g. '1.5 MiB'."""
    for unit in ("B", "KiB", "MiB"):
        if abs(n) < 1024:
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} GiB"


@dataclasses.dataclass
class ResourceInfo:
    """One logical resource in the report: its pins, shape, bytes, lifetime and what it shares."""

    name: str                   # 'Pass.pin' of the writer
    pins: list[str]             # writer then readers
    format: str | None          # None for buffers
    size: tuple[int, int]
    layers: int
    bytes: int
    aliased_with: list[str]     # other resources sharing the same GPU object
    kind: str = "texture"
    lifetime: tuple[int, int] = (0, 0)
    marked: bool = False
    internal: bool = False


@dataclasses.dataclass
class CompileReport:
    """Structured fields plus a readable `str()`. Subsystems append to `left_out` and `extra`."""

    graph: str
    size: tuple[int, int]
    views: int
    order: list[str]
    pruned: dict[str, str]
    resources: list[ResourceInfo]
    total_bytes: int
    unaliased_bytes: int
    defines: dict[str, dict]
    outputs: list[str]
    unavailable: dict[str, str] = dataclasses.field(default_factory=dict)
    left_out: list[str] = dataclasses.field(default_factory=list)
    extra: list = dataclasses.field(default_factory=list)
    timing: str = ""
    stages: dict = dataclasses.field(default_factory=dict)      # compile stage -> CPU ms
    barriers: dict = dataclasses.field(default_factory=dict)    # pass -> memory barrier before it
    nonfinite: dict = dataclasses.field(default_factory=dict)   # counting pass -> samples set to 0 so far

    @property
    def bytes_saved(self) -> int:
        return self.unaliased_bytes - self.total_bytes

    @property
    def aliased_fraction(self) -> float:
        """Allocated bytes over the bytes without aliasing (1.0 = nothing shared)."""
        return self.total_bytes / self.unaliased_bytes if self.unaliased_bytes else 1.0

    def as_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["extra"] = [e.as_dict() if hasattr(e, "as_dict") else str(e) for e in self.extra]
        d["bytes_saved"] = self.bytes_saved
        return d

    def __str__(self) -> str:
        w, h = self.size
        lines = [f"render graph '{self.graph}': {w}x{h} x {self.views} view(s)",
                 f"order: {' -> '.join(self.order) or '(nothing runs)'}"]
        if self.pruned:
            lines.append("pruned:")
            lines += [f"  {p}: {why}" for p, why in self.pruned.items()]
        lines.append(f"outputs: {', '.join(self.outputs) or '(none)'}")
        for ref, why in self.unavailable.items():
            lines.append(f"  {ref} not produced: {why}")
        lines.append("resources:")
        width = max((len(r.name) for r in self.resources), default=4)
        for r in self.resources:
            shape = (f"{r.format} {r.size[0]}x{r.size[1]}x{r.layers}" if r.kind == "texture"
                     else "buffer")
            tags = [t for t, on in (("output", r.marked), ("internal", r.internal)) if on]
            alias = f"  shares with {', '.join(r.aliased_with)}" if r.aliased_with else ""
            readers = f"  -> {', '.join(r.pins[1:])}" if len(r.pins) > 1 else ""
            lines.append(f"  {r.name:<{width}}  {shape:<24} {human_bytes(r.bytes):>10}"
                         f"  [{r.lifetime[0]},{r.lifetime[1]}]{' ' + ','.join(tags) if tags else ''}"
                         f"{readers}{alias}")
        lines.append(f"memory: {human_bytes(self.total_bytes)} allocated, {human_bytes(self.unaliased_bytes)} "
                     f"without aliasing, {human_bytes(self.bytes_saved)} saved "
                     f"({100 * self.aliased_fraction:.0f}% of unaliased)")
        defs = {p: d for p, d in self.defines.items() if d}
        if defs:
            lines.append("defines:")
            lines += [f"  {p}: " + ", ".join(f"{k}={v}" for k, v in d.items()) for p, d in defs.items()]
        if self.barriers:
            lines.append("barriers: " + "; ".join(f"{p}: {b}" for p, b in self.barriers.items()))
        if self.nonfinite:
            lines.append("non-finite samples set to 0 (GPU counters, as of this report): "
                         + ", ".join(f"{p} {n}" for p, n in self.nonfinite.items()))
        if self.stages:
            lines.append("compile stages: " + ", ".join(f"{k} {v:.1f} ms" for k, v in self.stages.items()))
        if self.left_out:
            lines.append("left out:")
            lines += [f"  {x}" for x in self.left_out]
        if self.timing:
            lines.append(f"timing: {self.timing}")
        for e in self.extra:
            lines += _format_entry(e) if isinstance(e, dict) else [str(e).rstrip()]
        return "\n".join(lines)


def _format_entry(d: dict, indent: str = "") -> list[str]:
    """A dict entry (e.g. GpuScene.report()) as indented 'key: value' lines."""
    out = []
    for k, v in d.items():
        if isinstance(v, dict) and v:
            out.append(f"{indent}{k}:")
            out += _format_entry(v, indent + "  ")
        elif isinstance(v, float):
            out.append(f"{indent}{k}: {v:.4g}")
        elif isinstance(v, (list, tuple)):
            out.append(f"{indent}{k}: {', '.join(map(str, v)) or '(none)'}")
        else:
            out.append(f"{indent}{k}: {v}")
    return out
