#!/bin/bash
# device call 15: the ray passes take one view per workgroup under view reuse (diag15.py: variants): tauray, clean preset,
# 64 views of 512x683 and stereo 2x1440x1600, GPU ms per pass per variant
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout 400 python3 benchmarks/results/gpu_2026-12-07b/diag15.py .scenes/tauray_test.glb 20 $OUT/diag15.json 2>&1 \
  | grep -v -i warn | cut -c1-1500 | tee $OUT/diag15.log
date
timeout ${LIMIT64:-250} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT --dispatches 5 \
  > $OUT/view_reuse64.log 2>&1
grep -v -i warn $OUT/view_reuse64.log | tail -6 | cut -c1-300; date
