#!/bin/bash
# device call 5 (the session's last ~300 s): 64 views of 512x683, the default reuse against
# Decision.reuse_delta_lobes (tauray's floor, Material.005, is a smooth dielectric: roughness 0, SHADOWS);
# a 16 x 16 spp reference to fit the time (FLIP comparable between these rows only)
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; date
timeout ${LIMIT64:-190} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT \
  --reference-frames 16 --variants "Decision.reuse_delta_lobes=True" > $OUT/view_reuse64.log 2>&1
grep -v -i warn $OUT/view_reuse64.log | grep -v "%|" | tail -6 | cut -c1-300; date
