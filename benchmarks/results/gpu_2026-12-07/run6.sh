#!/bin/bash
# device call (run5.sh cut again: ~300 s of device time left after six failed starts): rays with the skip compiled in
# and out (spheres, tauray; BVH4, 1920x1080, stats), then the path tracer on the spheres and tauray at 1 spp, d876cd6 (.ab/prev) against this tree
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout 100 python3 -m benchmarks rays --scenes .scenes/MetalRoughSpheresNoTextures.glb,.scenes/tauray_test.glb --stats --rounds 2 --variants "skip:RQ_CONVEX_SKIP=1|noskip:RQ_CONVEX_SKIP=0" > $OUT/rays.log 2>&1
grep -v -i warn $OUT/rays.log | tail -9 | cut -c1-700; cp benchmarks/results/rays.json $OUT/rays_skip.json; date
timeout 100 python3 tools/pt_variants.py $OUT/pt.jsonl --measures spheres,tauray --rounds 2 --frames 15 --timeout 45 prev base > $OUT/pt.log 2>&1
grep -v -i warn $OUT/pt.log | tail -4 | cut -c1-500; date
