#!/bin/bash
# device call (run4.sh cut to what issue 33 needs, after failed starts left ~750 s): rays with the skip compiled in
# and out (spheres, tauray; BVH4, 1920x1080, stats); the path tracer on the spheres and tauray at 1 and 4 spp,
# d876cd6 (.ab/prev) against this tree, A B A B; the spheres side by side with Mitsuba 3 principled
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout 120 python3 -m benchmarks rays --scenes .scenes/MetalRoughSpheresNoTextures.glb,.scenes/tauray_test.glb --stats --rounds 2 --variants "skip:RQ_CONVEX_SKIP=1|noskip:RQ_CONVEX_SKIP=0" > $OUT/rays.log 2>&1
grep -v -i warn $OUT/rays.log | tail -9 | cut -c1-700; cp benchmarks/results/rays.json $OUT/rays_skip.json; date
timeout 150 python3 tools/pt_variants.py $OUT/pt.jsonl --measures spheres,tauray --spp 1,4 --rounds 2 --frames 15 --timeout 60 prev base > $OUT/pt.log 2>&1
grep -v -i warn $OUT/pt.log | tail -4 | cut -c1-500; date
mkdir -p /tmp/mi && tar -xJf .peer/mitsuba-slim.tar.xz -C /tmp/mi
timeout 70 python3 .peer/pt_peer.py rayvr .scenes/MetalRoughSpheresNoTextures.glb .peer/cameras/spheres.json $OUT/rayvr_spheres.json > $OUT/rayvr_spheres.log 2>&1
cat $OUT/rayvr_spheres.json | cut -c1-600; echo; date
MI_BSDF=principled PYTHONPATH=/tmp/mi timeout 90 python3 .peer/mitsuba_peer.py .peer/spheres.npz cuda_ad_rgb 1920x1080 > $OUT/mitsuba_spheres.json 2> $OUT/mitsuba_spheres.log
cat $OUT/mitsuba_spheres.json | cut -c1-600; echo; date
