#!/bin/bash
# device call 10: tauray with and without reuse, stereo 2x1440x1600 and 64 x 512x683, the reused pixels now left to SVGF
# by the ray passes' fills and the composite
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout ${LIMIT:-330} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views ${VIEWS:-2,64} --out $OUT > $OUT/view_reuse.log 2>&1
grep -v -i warn $OUT/view_reuse.log | tail -8 | cut -c1-420; date
