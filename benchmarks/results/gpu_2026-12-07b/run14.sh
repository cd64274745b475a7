#!/bin/bash
# device call 14: where RTShadows' time goes under view reuse at 64 views of 512x683 (tauray, clean preset):
# diag14.py's decision kinds and Shadows ms per configuration
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout 400 python3 benchmarks/results/gpu_2026-12-07b/diag14.py .scenes/tauray_test.glb 512 683 20 $OUT/diag14.json 2>&1 \
  | grep -v -i warn | cut -c1-1500 | tee $OUT/diag14.log
date
