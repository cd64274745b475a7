#!/bin/bash
# device call 16: tauray, clean preset, view reuse. 1) diag15.py's workgroup variants of the one-view-tile
# default (GPU ms per pass; 64 views of 512x683 and stereo 2x1440x1600); 2) `view_reuse` at 64 views with FLIP:
# the default against glossier lobes reused (reuse_lobe_fraction 1 and 4, reuse_min_roughness 0.25) and
# sources every 3rd column and row
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout ${LIMITD:-240} python3 benchmarks/results/gpu_2026-12-07b/diag15.py .scenes/tauray_test.glb 20 $OUT/diag15.json 2>&1 \
  | grep -v -i warn | cut -c1-1500 | tee $OUT/diag15.log
date
timeout ${LIMIT64:-330} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT --dispatches 5 \
  --variants "${VARIANTS:-Decision.reuse_lobe_fraction=1;Decision.reuse_lobe_fraction=4;Decision.reuse_min_roughness=0.25;Decision.source_stride=3}" \
  > $OUT/view_reuse64.log 2>&1
grep -v -i warn $OUT/view_reuse64.log | tail -9 | cut -c1-300; date
