#!/bin/bash
# device call 1: the path tracer, raw hybrid and 64 views at 9c5360f against 44e709f (.ab/old); BVH4 against BVH8 rays with per-ray stats
export RAYVR_COMMIT=${RAYVR_COMMIT:-9c5360f}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
export GPU_BENCH_READY=1
nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
bash tools/gpu-bench i36 > $OUT/i36.log 2>&1
grep -v -i warn $OUT/i36.log | tail -4; date
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1
timeout 200 python3 -m benchmarks rays --scenes .scenes/tauray_test.glb,.scenes/MetalRoughSpheresNoTextures.glb --bvh-layouts bvh4,bvh8 --stats > $OUT/rays.log 2>&1
grep -v -i warn $OUT/rays.log | tail -30; date
cp -r benchmarks/results/rays.* $OUT/ 2>/dev/null
