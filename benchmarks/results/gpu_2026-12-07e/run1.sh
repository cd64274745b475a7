#!/bin/bash
# device call 1 (session 29, rayvr bd9b649: SVGF filters over a list under reuse): 64 views of 512x683, GPU ms per
# dispatch at the default stride 4, against SVGF.filter_list=False (the image-wide filter), Decision.reuse_delta_lobes
# (tauray's floor, Material.005, is a smooth dielectric: roughness 0, SHADOWS) and Shadows over the compaction's list;
# a 16 x 16 spp reference to fit the time (FLIP comparable between these rows only)
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt; date
timeout ${LIMIT64:-450} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT \
  --reference-frames 16 --dispatches 5 --variants "${VARIANTS:-SVGF.filter_list=False;Decision.reuse_delta_lobes=True;Shadows.dispatch_mode=list}" > $OUT/view_reuse64.log 2>&1
grep -v -i warn $OUT/view_reuse64.log | grep -v "%|" | tail -6 | cut -c1-300; date
