"""Study sizes for the machine at hand: what `rayvr converge` and `rayvr tune` render when not
told, chosen so that the study of the built-in Cornell box took about a minute. With probe GI and
SVGF among its 28 configurations it takes about 8 minutes on llvmpipe (2 cores; 1.5 with the
references and floors cached): the probe rows render most slowly there.

On llvmpipe (`gpu.caps.is_software`, ~0.45 M paths of 8 bounces per second on 2 cores) that is 2
views of 32x32, a 64 x 16 spp reference and 16-frame progressive curves; on a GPU, 2 views of
720x800 (a quarter of the Valve Index's pixels) and a 256 x 16 spp reference. Bigger scenes take
longer; every figure can be given instead, and the report says which were chosen and why.
"""
from __future__ import annotations

import dataclasses


@dataclasses.dataclass(frozen=True)
class MachineDefaults:
    """Sizes and frame counts for one kind of machine."""

    kind: str
    size: tuple[int, int]
    reference_frames: int
    reference_spp: int
    frames: int
    timing_frames: int
    warmup: int
    motion_frames: int
    motion_samples: int
    progressive_frames: int

    def note(self, chosen: dict) -> str:
        """One line saying what was chosen for this machine (`chosen`: option -> value used)."""
        parts = ", ".join(f"{k} {v}" for k, v in chosen.items())
        return f"defaults for {self.kind} (sized for the Cornell box; give options to change): {parts}"


SOFTWARE = MachineDefaults("llvmpipe (software rendering)", (32, 32), 64, 16, 4, 10, 2, 16, 2, 16)
HARDWARE = MachineDefaults("a GPU", (720, 800), 256, 16, 4, 30, 5, 32, 3, 128)


def machine_defaults(gpu) -> MachineDefaults:
    """SOFTWARE on llvmpipe, else HARDWARE."""
    return SOFTWARE if gpu.caps.is_software else HARDWARE
