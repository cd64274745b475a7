#!/bin/bash
# device call 12: tauray, clean preset, view reuse at 3752f6c+ (glossy pixels share the source's light samples), with
# and without that sharing; VIEWS 64 (512x683) adds the ray passes over the list (the image from 73ccd0c; calls
# 10-12 ran before it, at a62016e, when the list was the default) and sources every 3rd column and row; VIEWS 2
# (1440x1600) the sharing only
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
OFF="Decision.share_light_samples=False,Shadows.share_light_samples=False"
V=${VIEWS:-64}
if [ -z "${VARIANTS+x}" ]; then
  if [ "$V" = 2 ]; then VARIANTS="$OFF"; else VARIANTS="$OFF;Shadows.dispatch_mode=list;Decision.source_stride=3"; fi
fi
[ "$VARIANTS" = off ] && VARIANTS="$OFF"
timeout ${LIMIT:-540} python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views $V --out $OUT \
  --variants "$VARIANTS" > $OUT/view_reuse$V.log 2>&1
grep -v -i warn $OUT/view_reuse$V.log | tail -8 | cut -c1-560; date
