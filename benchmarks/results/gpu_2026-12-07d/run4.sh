#!/bin/bash
# device call 4 (rayvr 8829fe3): 64 views of 512x683, sources every 5th and every 8th row and column
# (stride 8: the corner view alone is the source), with FLIP; the rows print as they finish
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; date
timeout ${LIMIT64:-330} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT \
  --variants "${VARIANTS:-Decision.source_stride=5;Decision.source_stride=8}" > $OUT/view_reuse64.log 2>&1
grep -v -i warn $OUT/view_reuse64.log | grep -v "%|" | tail -8 | cut -c1-300; date
