"""Times the error study's reference graph (tauray, 2x720x800) under PathTracer property sets."""
import json, sys, time
import rayvr as rv
from rayvr.gpu import get_context
from rayvr.renderer import Renderer
from rayvr.study.reference import ReferenceSettings, reference_graph
from rayvr.study.timing import make_views, timed_frames

gpu = get_context()
scene = rv.load_scene(sys.argv[1])
size = tuple(int(x) for x in (sys.argv[2] if len(sys.argv) > 2 else "720x800").split("x"))
views = make_views(scene, 2, size)
sets = [
    dict(spp=16, b=8),
    dict(spp=16, b=8, compact=True),
    dict(spp=16, b=8, persistent=True),
    dict(spp=16, b=8, compact=True, sort_directions=True),
    dict(spp=16, b=3),
    dict(spp=1, b=8),
    dict(spp=1, b=8, compact=True),
    dict(spp=16, b=8, pixel_jitter=False),
    dict(spp=16, b=8, kernel="megakernel"),
]
for s in sets:
    s = dict(s)
    spp, b = s.pop("spp"), s.pop("b")
    g = reference_graph(ReferenceSettings(256, spp, b))
    if s:
        g.update_pass("PathTracer", s)
    t0 = time.perf_counter()
    try:
        with Renderer(scene, g, views=views, gpu=gpu) as r:
            t = timed_frames(r, 10 if spp > 1 else 40, 2, 0.5)
            print(json.dumps({"spp": spp, "bounces": b, **s, "frame_ms": round(t.frame_ms, 2),
                              "passes": {k: round(v, 2) for k, v in t.pass_ms.items()},
                              "wall_s": round(time.perf_counter() - t0, 1)}), flush=True)
    except Exception as e:
        print(json.dumps({"spp": spp, "bounces": b, **s, "error": repr(e)[:300]}), flush=True)
