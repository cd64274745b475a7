#!/bin/bash
# device call 2 prepared in session 32 (not run: no device machine): the working tree (RAYVR_COMMIT) on tauray, clean
# preset: 64 views of 512x683 with FLIP against the 16 x 16 spp reference (issue 34's error target), then stereo
# 2x1440x1600 with the default reference. Carry [".gl", ".whl", ".scenes"].
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt; date
mkdir -p $OUT/flip $OUT/s2
timeout 280 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT/flip \
  --reference-frames 16 --dispatches 5 > $OUT/flip/view_reuse64.log 2>&1
grep -v -i warn $OUT/flip/view_reuse64.log | grep -v "%|" | tail -5 | cut -c1-300; date
timeout 200 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 2 --out $OUT/s2 --dispatches 5 \
  --variants "Decision.work_tiles=False" > $OUT/s2/view_reuse2.log 2>&1
grep -v -i warn $OUT/s2/view_reuse2.log | grep -v "%|" | tail -6 | cut -c1-300; date
