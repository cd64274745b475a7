"""Where RTShadows' time goes under view reuse at 64 views (tauray, clean preset): the trace decision's
kinds per source and other views, and Shadows' GPU ms for independent views, reuse, reuse over the
compaction's list, reuse in one-view tiles, and the 16 source views alone (scattered cameras) against
16 neighbouring views."""
import json
import sys

import numpy as np

import rayvr as rv
from rayvr.xr.cameras import default_views
from rayvr.xr.views import ViewSet
from rayvr.cli.options import load_scene_arg

scene = load_scene_arg(sys.argv[1])
size = (int(sys.argv[2]), int(sys.argv[3])) if len(sys.argv) > 3 else (512, 683)
frames = int(sys.argv[4]) if len(sys.argv) > 4 else 20
vs64 = default_views(scene, 64, size)
cols = rv.xr.grid_for_views(64)[0]
sources = [v for v in range(64) if (v % cols) % 2 == 0 and (v // cols) % 2 == 0]
out = {}


def time(label, views, reuse, props=None, decision=False):
    g = rv.graphs.hybrid(preset="clean", reuse=reuse)
    for name, p in (props or {}).items():
        g.update_pass(name, p)
    if decision:
        g.mark_output("Decision.decision")
    with rv.Renderer(scene, g, views=views) as r:
        for _ in range(5):
            r.render()
        r.compiled.reset_profile() if hasattr(r.compiled, "reset_profile") else None
        for _ in range(frames):
            r.render()
        prof = r.profile()
        rays = r.compiled.ray_counts()
        row = {"passes": {n: round(s.mean_ms, 3) for n, s in prof.passes.items()}, "total": round(prof.total_ms, 3),
               "rays": int(sum(rays))}
        if decision:
            d = r.read_output("Decision.decision")[..., 0].astype(np.uint32)
            kinds = {}
            for cls, vs in (("sources", sources), ("others", [v for v in range(64) if v not in sources])):
                x = d[vs]
                k = x & 3
                kinds[cls] = {"none": int((k == 0).sum()), "trace": int(((k == 1) & ((x & 8) == 0)).sum()),
                              "trace_shared_light": int(((k == 1) & ((x & 8) != 0)).sum()),
                              "reuse": int((k == 2).sum()), "fill": int((k == 3).sum()),
                              "spread": int(((x & 4) != 0).sum())}
            row["decision"] = kinds
    out[label] = row
    print(label, json.dumps(row), flush=True)


time("independent 64", vs64, None)
time("reuse 64", vs64, "views", decision=True)
time("reuse 64, Shadows list", vs64, "views", {"Shadows": {"dispatch_mode": "list"}})
time("reuse 64, Shadows view_group 1", vs64, "views", {"Shadows": {"view_group": 1}})
time("reuse 64, Shadows view_group 4", vs64, "views", {"Shadows": {"view_group": 4}})
time("independent, the 16 sources", ViewSet([vs64.views[v] for v in sources]), None)
time("independent, 16 neighbours (rows 0-1)", ViewSet(vs64.views[:16]), None)
time("independent, the 16 sources, view_group 1", ViewSet([vs64.views[v] for v in sources]), None,
     {"Shadows": {"view_group": 1}})
json.dump(out, open(sys.argv[5] if len(sys.argv) > 5 else "diag14.json", "w"), indent=1)
