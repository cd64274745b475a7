#!/bin/bash
# device call 1: glass in the hybrid (transmissive materials REFLECTIONS by default, one transmission
# bounce, the composite with the scene's features) against 18776c9 (.ab/base: tools/ab_trees.py --src):
# tauray's stereo frame (frame_configs raw and clean, interleaved rounds) and the stereo view reuse with FLIP
# in both trees (the independent row's FLIP shows the glass)
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout 200 python3 tools/gpu_ab.py --base .ab/base --rounds 2 -- frame_configs --scene .scenes/tauray_test.glb \
  --configs "raw,clean" --frames 20 > $OUT/frame_ab.log 2>&1
grep -v -i warn $OUT/frame_ab.log | tail -14 | cut -c1-220; date
timeout 150 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 2 --out $OUT \
  > $OUT/view_reuse2.log 2>&1
grep -v -i warn $OUT/view_reuse2.log | tail -6 | cut -c1-400; date
mkdir -p $OUT/base
PYTHONPATH=/tmp/site:$PWD/.ab/base/src timeout 150 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb \
  --views 2 --out $OUT/base > $OUT/base/view_reuse2.log 2>&1
grep -v -i warn $OUT/base/view_reuse2.log | tail -6 | cut -c1-400; date
