#!/bin/bash
# device call 1: the convex skip (a ray leaving a triangle with its whole mesh behind it skips its own instance).
# rays: this tree with the skip compiled in and out (RQ_CONVEX_SKIP), BVH4, 1920x1080, with node/triangle/instance stats;
# path tracer (pt_peer's cameras, 1920x1080, 1 and 4 spp) and raw hybrid: d876cd6 (.ab/prev) against this tree, A B A B
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout 200 python3 -m benchmarks rays --scenes .scenes/MetalRoughSpheresNoTextures.glb,.scenes/tauray_test.glb --stats --variants "skip:RQ_CONVEX_SKIP=1|noskip:RQ_CONVEX_SKIP=0" > $OUT/rays.log 2>&1
grep -v -i warn $OUT/rays.log | tail -9; cp benchmarks/results/rays.json $OUT/rays_skip.json; date
timeout 330 python3 tools/pt_variants.py $OUT/pt.jsonl --measures spheres,tauray,cornell,hybrid --spp 1,4 --passes --rounds 2 --frames 15 --timeout 80 prev base > $OUT/pt.log 2>&1
grep -v -i warn $OUT/pt.log | tail -4 | cut -c1-600; date
