#!/bin/bash
# device call: stereo 2x1440x1600 on tauray with and without reuse (SVGF now spreads the source eye's filtered light);
# the spheres side by side with Mitsuba 3 principled (pt_peer's cameras, 1920x1080, 1/4/8/32/256 spp)
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout 200 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 2 --out $OUT > $OUT/view_reuse2.log 2>&1
grep -v -i warn $OUT/view_reuse2.log | tail -7 | cut -c1-400; date
mkdir -p /tmp/mi && tar -xJf .peer/mitsuba-slim.tar.xz -C /tmp/mi
timeout 70 python3 .peer/pt_peer.py rayvr .scenes/MetalRoughSpheresNoTextures.glb .peer/cameras/spheres.json $OUT/rayvr_spheres.json > $OUT/rayvr_spheres.log 2>&1
cut -c1-600 $OUT/rayvr_spheres.json; echo; date
MI_BSDF=principled PYTHONPATH=/tmp/mi timeout 100 python3 .peer/mitsuba_peer.py .peer/spheres.npz cuda_ad_rgb 1920x1080 > $OUT/mitsuba_spheres.json 2> $OUT/mitsuba_spheres.log
cut -c1-600 $OUT/mitsuba_spheres.json; echo; date
