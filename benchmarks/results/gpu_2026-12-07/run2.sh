#!/bin/bash
# device call 2: issue 33's side-by-side, this tree against Mitsuba 3 (../shared/tools/pt_peer.py, mitsuba_peer.py;
# 1920x1080, max_bounces 3 = max_depth 4, RR off): Cornell against Mitsuba diffuse, tauray and the spheres against principled
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
mkdir -p /tmp/mi && tar -xJf .peer/mitsuba-slim.tar.xz -C /tmp/mi
date
declare -A F=([cornell]=.scenes/cornell/cornell_box.gltf [tauray]=.scenes/tauray_test.glb [spheres]=.scenes/MetalRoughSpheresNoTextures.glb)
declare -A B=([cornell]=diffuse [tauray]=principled [spheres]=principled)
for s in cornell tauray spheres; do
  timeout 100 python3 .peer/pt_peer.py rayvr ${F[$s]} .peer/cameras/$s.json $OUT/rayvr_$s.json > $OUT/rayvr_$s.log 2>&1
  MI_BSDF=${B[$s]} PYTHONPATH=/tmp/mi timeout 120 python3 .peer/mitsuba_peer.py .peer/$s.npz cuda_ad_rgb 1920x1080 > $OUT/mitsuba_$s.json 2> $OUT/mitsuba_$s.log
  echo "$s"; cat $OUT/rayvr_$s.json | cut -c1-400; echo; cat $OUT/mitsuba_$s.json | cut -c1-400; echo; date
done
