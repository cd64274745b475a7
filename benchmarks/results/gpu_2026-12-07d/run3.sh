#!/bin/bash
# device call 3 (rayvr 7th commit of the session, glass back to SHADOWS by default): tauray, clean preset,
# view reuse with FLIP in stereo 2x1440x1600 and at 64 views of 512x683 (defaults: sources every third row
# and column; variant: every fourth), after SVGF's demodulation fixes (49cff11, 5ae154f)
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
mkdir -p $OUT/s2; date
timeout 120 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 2 --out $OUT/s2 \
  > $OUT/view_reuse2.log 2>&1
grep -v -i warn $OUT/view_reuse2.log | tail -6 | cut -c1-400; date
timeout ${LIMIT64:-400} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT \
  --variants "${VARIANTS:-Decision.source_stride=4}" > $OUT/view_reuse64.log 2>&1
grep -v -i warn $OUT/view_reuse64.log | tail -7 | cut -c1-300; date
