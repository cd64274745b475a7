#!/bin/bash
# device calls 16-17: tauray, clean preset, view reuse at 64 views of 512x683, `view_reuse` with FLIP and
# per-dispatch GPU ms. Call 16 (default VARIANTS): the ray passes' workgroups compacting their traced pixels
# (Decision.compact_tile 8, 16 and 32). Call 17: VARIANTS="Decision.reuse_lobe_fraction=1;..." (glossier lobes
# reused) and LIMITD=200: then also diag15.py's workgroup variants of the one-view-tile default (GPU ms per pass)
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout ${LIMIT64:-420} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT --dispatches 5 \
  --variants "${VARIANTS:-Decision.compact_tile=16;Decision.compact_tile=32;Decision.compact_tile=8}" \
  > $OUT/view_reuse64.log 2>&1
grep -v -i warn $OUT/view_reuse64.log | tail -9 | cut -c1-300; date
if [ "${LIMITD:-0}" -gt 0 ]; then
timeout $LIMITD python3 benchmarks/results/gpu_2026-12-07b/diag15.py .scenes/tauray_test.glb 20 $OUT/diag15.json 2>&1 \
  | grep -v -i warn | cut -c1-1500 | tee $OUT/diag15.log
date
fi
