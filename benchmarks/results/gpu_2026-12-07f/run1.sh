#!/bin/bash
# device call 1 (prepared in session 30, not run: no device machine was lent): tauray, clean preset, 64 views of
# 512x683, `view_reuse --dispatches 5`, one tree after another with a 1 x 1 spp reference (timing only):
# t0 f0c1e67 (session 29's frame), t1 1cf2dd4 (SVGF's scratch texels and the composite's lobes left unwritten where
# SVGF spreads), t2 6099a8f (+ the decision's tap mask), head = .ab/t3, f394dc2 (+ the spread's history read through
# the decision texel, 0163c91, and the decision's work tiles, 745dfbf) with the variants Decision.work_tiles=False
# (0163c91's frame) and light samples not shared; then head with the 16 x 16 spp reference (FLIP comparable with
# gpu_2026-12-07e's 64-view rows); then stereo. First, here:
#   for c in f0c1e67:t0 1cf2dd4:t1 6099a8f:t2 f394dc2:t3; do python3 tools/ab_trees.py --src ${c%%:*} ${c##*:}; done
# and carry [".gl", ".whl", ".scenes", ".ab"] with RAYVR_COMMIT=<head's hash>.
cd "$(dirname "$0")/../../.."
part=${1:-all}   # trees | flip | all (one device call allows 600 s)
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt; date
if [ $part != flip ]; then
for t in ${TREES:-t0 head t1 t2}; do
  s=$PWD/.ab/t3/src; v=""; [ $t != head ] && s=$PWD/.ab/$t/src   # head: f394dc2 (.ab/t3)
  [ $t = head ] && v="Decision.work_tiles=False;Decision.share_light_samples=False,Shadows.share_light_samples=False"
  mkdir -p $OUT/$t
  PYTHONPATH=/tmp/site:$s timeout 120 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT/$t \
    --reference-frames 1 --reference-spp 1 --dispatches 5 ${v:+--variants "$v"} > $OUT/$t/view_reuse64.log 2>&1
  echo "== $t"; grep -v -i warn $OUT/$t/view_reuse64.log | grep -v "%|" | grep "a frame" | cut -c1-200
done; date
fi
[ $part = trees ] && exit 0
mkdir -p $OUT/flip
timeout 200 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT/flip \
  --reference-frames 16 --dispatches 5 > $OUT/flip/view_reuse64.log 2>&1
grep -v -i warn $OUT/flip/view_reuse64.log | grep -v "%|" | tail -5 | cut -c1-300; date
# stereo 2x1440x1600 at head, with FLIP against the benchmark's default reference (as gpu_2026-12-07e's run3.sh)
mkdir -p $OUT/s2
timeout 150 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 2 --out $OUT/s2 --dispatches 5 \
  > $OUT/s2/view_reuse2.log 2>&1
grep -v -i warn $OUT/s2/view_reuse2.log | grep -v "%|" | tail -6 | cut -c1-300; date
