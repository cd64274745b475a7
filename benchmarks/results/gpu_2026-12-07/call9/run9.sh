#!/bin/bash
# device call 9 (as run, one command line): rays with the convex skip in and out, diffuse rays in the queue and
# persistent layouts
source tools/gpu-preamble.sh; export RAYVR_COMMIT=5e60e36; for lay in queue persistent; do timeout 120 python3 -m benchmarks rays --scenes .scenes/MetalRoughSpheresNoTextures.glb,.scenes/tauray_test.glb --diffuse-layout $lay --rounds 2 --variants "skip:RQ_CONVEX_SKIP=1|noskip:RQ_CONVEX_SKIP=0" --out $OUT/$lay > $OUT/rays_$lay.log 2>&1; grep -v -i warn $OUT/rays_$lay.log | grep -E "glb" | cut -c1-200; done; date
