#!/bin/bash
# device call: run6 (rays with the convex skip compiled in and out; the path tracer, d876cd6 (.ab/prev) against this
# tree) and 64 views of tauray with and without reuse, SVGF now denoising reused light once, in the source views
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout 200 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT > $OUT/view_reuse64.log 2>&1
grep -v -i warn $OUT/view_reuse64.log | tail -7 | cut -c1-400; date
timeout 100 python3 -m benchmarks rays --scenes .scenes/MetalRoughSpheresNoTextures.glb,.scenes/tauray_test.glb --stats --rounds 2 --variants "skip:RQ_CONVEX_SKIP=1|noskip:RQ_CONVEX_SKIP=0" > $OUT/rays.log 2>&1
grep -v -i warn $OUT/rays.log | tail -9 | cut -c1-700; cp benchmarks/results/rays.json $OUT/rays_skip.json; date
timeout 100 python3 tools/pt_variants.py $OUT/pt.jsonl --measures spheres,tauray --rounds 2 --frames 15 --timeout 45 prev base > $OUT/pt.log 2>&1
grep -v -i warn $OUT/pt.log | tail -4 | cut -c1-500; date
# the same 64 views in 37b7065 (.ab/head: SVGF filtering every view), if the call has time left
RAYVR_SRC=$PWD/.ab/head/src PYTHONPATH=/tmp/site:$PWD/.ab/head/src timeout 150 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT/head > $OUT/view_reuse64_head.log 2>&1
grep -v -i warn $OUT/view_reuse64_head.log | tail -7 | cut -c1-400; date
