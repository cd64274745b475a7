#!/bin/bash
# device call 13: tauray, clean preset, view reuse with the ray passes' workgroups taking the source views first
# and SVGF's a-trous iterations leaving unfiltered pixels alone; per-dispatch GPU ms (--dispatches); 64 views
# of 512x683 with the grid order as before (Decision.source_views_first=False) and sources every 3rd column and
# row; then stereo 2x1440x1600
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout ${LIMIT64:-460} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT --dispatches 5 \
  --variants "${VARIANTS:-Decision.source_views_first=False;Decision.source_stride=3}" > $OUT/view_reuse64.log 2>&1
grep -v -i warn $OUT/view_reuse64.log | tail -8 | cut -c1-300; date
timeout ${LIMIT2:-120} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 2 --out $OUT/stereo --dispatches 5 \
  > $OUT/view_reuse2.log 2>&1
grep -v -i warn $OUT/view_reuse2.log | tail -6 | cut -c1-300; date
