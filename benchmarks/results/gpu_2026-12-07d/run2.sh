#!/bin/bash
# device call 2 (warm after call 1, rayvr 5ae154f): where the glass's Reflections pass spends its 1.9 ms at
# stereo 2x1440x1600 (per dispatch; the list form and no transmission bounce as variants of the reuse row),
# then 64 views of 512x683 with FLIP at the defaults and with sources every 4th row and column
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; export GPU_BENCH_READY=1
mkdir -p $OUT/s2; date
timeout 150 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 2 --out $OUT/s2 --dispatches 5 \
  --variants "Reflections.dispatch_mode=list;Reflections.transmission_bounces=0" > $OUT/view_reuse2.log 2>&1
grep -v -i warn $OUT/view_reuse2.log | tail -8 | cut -c1-700; date
timeout ${LIMIT64:-370} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT \
  --variants "${VARIANTS:-Decision.source_stride=4}" > $OUT/view_reuse64.log 2>&1
grep -v -i warn $OUT/view_reuse64.log | tail -7 | cut -c1-300; date
