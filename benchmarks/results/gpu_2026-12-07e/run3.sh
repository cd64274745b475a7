#!/bin/bash
# device call 3 (prepared, not run: the session's device time was spent): the defaults after the composite's list
# and the tap mask were taken out (delta lobes reused, SVGF over its filter list), tauray, clean preset, view reuse
# with FLIP and GPU ms per dispatch: stereo 2x1440x1600 (64 x 16 spp reference) and 64 views of 512x683
# (16 x 16 spp reference, as calls 1 and 2), each against its independent views
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
mkdir -p $OUT/s2; date
timeout 150 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 2 --out $OUT/s2 --dispatches 5 \
  > $OUT/view_reuse2.log 2>&1
grep -v -i warn $OUT/view_reuse2.log | grep -v "%|" | tail -6 | cut -c1-300; date
timeout ${LIMIT64:-300} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT \
  --reference-frames 16 --dispatches 5 ${VARIANTS64:+--variants "$VARIANTS64"} > $OUT/view_reuse64.log 2>&1
grep -v -i warn $OUT/view_reuse64.log | grep -v "%|" | tail -5 | cut -c1-300; date
