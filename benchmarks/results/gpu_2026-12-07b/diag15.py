"""The ray passes' workgroup shape under view reuse (tauray, clean preset): GPU ms per pass for
reuse graphs with pass properties overridden, 64 views of 512x683 and a stereo pair of 1440x1600."""
import json
import sys

import rayvr as rv
from rayvr.cli.options import load_scene_arg
from rayvr.xr.cameras import default_views

scene = load_scene_arg(sys.argv[1])
frames = int(sys.argv[2]) if len(sys.argv) > 2 else 20
quick = len(sys.argv) > 4 and sys.argv[4] == "quick"
out = {}
VARIANTS64 = [
    ("independent", None, {}),
    ("reuse", "views", {}),
    ("reuse, Decision one_view_tiles False", "views", {"Decision": {"one_view_tiles": False}}),
    ("reuse, Composite probe_view_group 1", "views", {"Composite": {"probe_view_group": 1}}),
    ("reuse, Shadows tile 16x2", "views", {"Shadows": {"tile": [16, 2]}}),
    ("reuse, Shadows tile 4x8", "views", {"Shadows": {"tile": [4, 8]}}),
    ("reuse, Shadows tile 8x8", "views", {"Shadows": {"tile": [8, 8]}}),
    ("reuse, source_stride 3", "views", {"Decision": {"source_stride": 3}}),
    ("reuse, source_stride 4", "views", {"Decision": {"source_stride": 4}}),
]
VARIANTS2 = [("independent", None, {}), ("reuse", "views", {})]


def time(label, views, reuse, props):
    g = rv.graphs.hybrid(preset="clean", reuse=reuse)
    for name, p in props.items():
        g.update_pass(name, p)
    with rv.Renderer(scene, g, views=views) as r:
        for _ in range(5):
            r.render()
        r.compiled.reset_profile()
        for _ in range(frames):
            r.render()
        prof = r.profile()
        row = {"passes": {n: round(s.mean_ms, 3) for n, s in prof.passes.items()}, "total": round(prof.total_ms, 3),
               "rays": int(sum(r.compiled.ray_counts()))}
    out[label] = row
    print(label, json.dumps(row), flush=True)


for n, size, variants in ((64, (16, 16) if quick else (512, 683), VARIANTS64),
                          (2, (32, 32) if quick else (1440, 1600), VARIANTS2)):
    vs = default_views(scene, n, size)
    for label, reuse, props in variants:
        time(f"{n} views: {label}", vs, reuse, props)
json.dump(out, open(sys.argv[3] if len(sys.argv) > 3 else "diag15.json", "w"), indent=1)
