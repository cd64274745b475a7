#!/bin/bash
# device call 11: tauray, 64 x 512x683 (VIEWS), clean preset, with and without reuse at the spread flag, and reuse
# variants (VARIANTS, benchmarks view_reuse --variants): the ray passes over the whole image instead of the list,
# sources every 3rd column and row, every non-transmissive surface reused
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout ${LIMIT:-540} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views ${VIEWS:-64} --out $OUT \
  --variants "${VARIANTS-Shadows.dispatch_mode=image;Decision.source_stride=3;Decision.reuse_min_roughness=0}" > $OUT/view_reuse.log 2>&1
grep -v -i warn $OUT/view_reuse.log | tail -9 | cut -c1-520; date
