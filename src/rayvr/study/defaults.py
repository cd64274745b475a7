"""Study sizes for the machine at hand: what `rayvr converge` and `rayvr tune` render when not
told, chosen so that the study of the built-in Cornell box took about a minute. With the probe-GI
rows among its configurations it takes several minutes on llvmpipe (2 cores): they render most
slowly there. So on llvmpipe the standard list leaves out the hybrid levels through SVGF
(`denoised_levels`; 8 rows, half of them with probe GI), and the note says so.

On llvmpipe (`gpu.caps.is_software`, ~0.45 M paths of 8 bounces per second on 2 cores) that is 2
views of 32x32, a reference rendered 64 x 16 spp at a time until converged (at most 1024 frames
or 60 s), one judged frame along the trajectory (each needs its own reference), bias floors at
1/16 of the reference's first 64 frames (a probe-GI floor of 256 frames took 37 s there: the
probe update, whatever the image's size) and 16-frame progressive curves; on a GPU, 2 views of
720x800 (a quarter of the Valve Index's pixels), a reference rendered 256 x 16 spp at a time until
converged (at most 16384 frames or 960 s of rendering, summed over the runs that resume it from
the cache) and floors at 1/4 of its first 256 frames. Bigger scenes take longer; every figure can
be given instead, and the report says which were chosen and why.
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
    reference_max_frames: int = 16384   # the reference renders on until converged, up to this many frames
    # or until this much rendering time (each reference, summed over its runs: tauray/test.glb at
    # 2x720x800 converges after about 5,100 frames of 16 spp, 12-14 minutes on one datacenter GPU;
    # benchmarks/RESULTS.md)
    reference_seconds: float = 960.0
    floor_fraction: float = 0.25    # of the reference's first-round paths per pixel, for each bias floor
    denoised_levels: bool = True    # rayvr.study.standard_configs' hybrid levels through SVGF
    probe_counts: tuple | None = None   # the probe GI rows' probes per axis (None: the pass's 8^3)

    def reference_settings(self, max_bounces: int = 8):
        """The reference these defaults render: `reference_frames` x `reference_spp` at a time
        until converged, up to `reference_max_frames` frames or `reference_seconds`."""
        from .reference import ReferenceSettings

        return ReferenceSettings(self.reference_frames, self.reference_spp, max_bounces,
                                 max_frames=max(self.reference_max_frames, self.reference_frames),
                                 max_seconds=self.reference_seconds)

    def note(self, chosen: dict, left_out: bool = False) -> str:
        """One line saying what was chosen for this machine (`chosen`: option -> value used;
        `left_out`: the standard list without the hybrid levels through SVGF)."""
        parts = ", ".join(f"{k} {v}" for k, v in chosen.items())
        if left_out:
            parts += ("; " if parts else "") + "the hybrid levels through SVGF left out (give them with --configs)"
        return f"defaults for {self.kind} (sized for the Cornell box; give options to change): {parts}"


SOFTWARE = MachineDefaults("llvmpipe (software rendering)", (32, 32), 64, 16, 4, 10, 2, 16, 1, 16,
                           reference_max_frames=1024, reference_seconds=60.0, floor_fraction=0.0625,
                           denoised_levels=False, probe_counts=(4, 4, 4))
HARDWARE = MachineDefaults("a GPU", (720, 800), 256, 16, 4, 30, 5, 32, 3, 128)


def machine_defaults(gpu) -> MachineDefaults:
    """SOFTWARE on llvmpipe, else HARDWARE."""
    return SOFTWARE if gpu.caps.is_software else HARDWARE
