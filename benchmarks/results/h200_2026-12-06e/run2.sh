#!/bin/bash
# device call 2: the explicit-lobe BSDF (base) against 44e709f (old) and HEAD (head): hybrid, 64 views,
# path tracer; then BVH4 against BVH8 (rays)
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1 RAYVR_COMMIT=${RAYVR_COMMIT:-wt}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout 300 python3 tools/pt_variants.py $OUT/explicit.jsonl --measures hybrid,views,cornell,tauray --passes --rounds 2 --frames 15 --timeout 80 old head base > $OUT/explicit.log 2>&1
date
timeout 240 python3 -m benchmarks rays --scenes .scenes/tauray_test.glb,.scenes/MetalRoughSpheresNoTextures.glb --bvh-layouts bvh4,bvh8 --rounds 2 --out $OUT/rays > $OUT/rays.log 2>&1
grep -v -i warn $OUT/rays.log | tail -14; date
