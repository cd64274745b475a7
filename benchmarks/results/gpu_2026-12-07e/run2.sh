#!/bin/bash
# device call 2 (session 29, rayvr 679d697: reuse_delta_lobes on by default, the decision's tap mask, the composite over the
# decision's list of pixels whose light is their own): tauray, clean
# preset, view reuse with FLIP and GPU ms per dispatch, stereo 2x1440x1600 (64 x 16 spp reference) and 64 views of
# 512x683 (16 x 16 spp reference, as call 1), each against its independent views; variants: stereo without the
# delta lobes' reuse, 64 views with the composite over the image
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
mkdir -p $OUT/s2; date
timeout 150 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 2 --out $OUT/s2 --dispatches 5 \
  --variants "${VARIANTS2:-Decision.reuse_delta_lobes=False}" > $OUT/view_reuse2.log 2>&1
grep -v -i warn $OUT/view_reuse2.log | grep -v "%|" | tail -7 | cut -c1-300; date
timeout ${LIMIT64:-300} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT \
  --reference-frames 16 --dispatches 5 --variants "${VARIANTS64:-Composite.pixel_list=False}" > $OUT/view_reuse64.log 2>&1
grep -v -i warn $OUT/view_reuse64.log | grep -v "%|" | tail -6 | cut -c1-300; date
