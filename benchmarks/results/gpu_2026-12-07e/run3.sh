#!/bin/bash
# device call 3 (session 29, the last ~200 s): 64 views of 512x683 at the tree with the decision's tap mask and
# without the composite's list, against independent views; a 1 x 16 spp reference (its FLIP is not comparable)
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; date
timeout ${LIMIT64:-120} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT \
  --reference-frames 1 --dispatches 5 > $OUT/view_reuse64.log 2>&1
grep -v -i warn $OUT/view_reuse64.log | grep -v "%|" | tail -5 | cut -c1-300; date
