"""Fit per-material effects to a GPU frame budget, then render with them.

    python examples/tune_budget.py                              # Cornell box, 2 x 64x64, 4 ms
    python examples/tune_budget.py scene.glb --size 1440x1600 --budget-ms 11.1 --report out/tune

The tuner renders every material at each effect level once (RASTER, SHADOWS, REFLECTIONS,
PATH_TRACED), splits the ray passes' GPU time and the image error (FLIP of the displayed image
at the headset's pixels per degree, against a converged, checked, cached path-traced reference)
by each material's pixels, and picks effects greedily by error reduction per millisecond until
the budget is met. The budget holds for the size it was tuned at. With --report the error study
(rayvr converge's) measures the standard configurations and the tuned one alike.
"""
from __future__ import annotations

import argparse

import rayvr as rv
from rayvr.cli.options import load_scene_arg, parse_size


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", nargs="?", help="glTF file or built-in scene name (default: Cornell box)")
    ap.add_argument("--size", default="64x64", help="per-eye size (default 64x64)")
    ap.add_argument("--budget-ms", type=float, default=4.0, help="GPU ms per frame (11.1 at 90 Hz; default 4)")
    ap.add_argument("--frames", type=int, default=5, help="timed frames per probe (default 5)")
    ap.add_argument("--reference-frames", type=int, default=64, help="frames of 16 spp of the reference (default 64)")
    ap.add_argument("--report", help="also measure the standard configurations and write a report here")
    args = ap.parse_args()

    scene = load_scene_arg(args.scene)
    size = parse_size(args.size)
    settings = rv.tune.ReferenceSettings(frames=args.reference_frames)
    with rv.Renderer(scene, rv.graphs.hybrid(), views=2, size=size) as r:
        tuned = rv.tune.tune_effects(r, budget_ms=args.budget_ms, frames=args.frames,
                                     reference=settings)               # sets the scene's effects
        print(tuned.table())
        print("\nsteps:", ", ".join(f"{s.material} {s.old.name}->{s.new.name} (+{s.added_ms:.3g} ms)"
                                    for s in tuned.steps) or "none")
        for _ in range(args.frames):
            r.render()
        print(f"\nrendering with the tuned effects:\n{r.profile()}")

    if args.report:
        configs = rv.tune.standard_configs(scene, settings) + [
            rv.tune.Config("tuned", dict(tuned.assignment), options={"path_bounces": settings.max_bounces})]
        study = rv.tune.StudySettings(frames=3, timing_frames=args.frames)
        results = rv.study.measure(scene, configs, views=2, size=size, reference=settings, settings=study)
        print(results.table())
        print(f"wrote {rv.tune.write_report(results, args.report, budget_ms=args.budget_ms)}")


if __name__ == "__main__":
    main()
