#!/bin/bash
# device calls prepared in session 32 (not run: no device machine): tauray, clean preset, 64 views of 512x683, `view_reuse --dispatches 5`, a 1 x 1 spp
# reference (timing only), one tree after another: `base` (.ab/base, 98ab2c3, session 31's end) and the working tree
# (`head`, RAYVR_COMMIT), the latter with VARIANTS. Build .ab/base here first:
#   python3 tools/ab_trees.py --src 98ab2c3 base
# and carry [".gl", ".whl", ".scenes", ".ab"].
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt; date
for t in ${TREES:-base head}; do
  s=$PWD/src; v=$VARIANTS; [ $t != head ] && s=$PWD/.ab/$t/src && v=
  mkdir -p $OUT/$t
  PYTHONPATH=/tmp/site:$s timeout ${LIMIT:-200} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 \
    --out $OUT/$t --reference-frames 1 --reference-spp 1 --dispatches 5 ${v:+--variants "$v"} \
    > $OUT/$t/view_reuse64.log 2>&1
  echo "== $t"; grep -v -i warn $OUT/$t/view_reuse64.log | grep -v "%|" | grep "a frame" | cut -c1-200
done; date
