#!/bin/bash
# device call 2: 9c5360f (.ab/head) against the triangle slots' alpha mode (158a051, .ab/slot) and that with the instances carrying their BLAS root and first triangle (working tree, base): path tracer, raw hybrid, 64 views, rays; the driver's program binaries
# (the binaries ran as .ab/dumpbin.py, since committed as tools/program_binaries.py)
export RAYVR_COMMIT=${RAYVR_COMMIT:-wt}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1
nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout 400 python3 tools/pt_variants.py $OUT/c2.jsonl --measures cornell,tauray,hybrid,views,rays --passes --rounds 2 --frames 15 --timeout 90 head slot base > $OUT/c2.log 2>&1
grep -v -i warn $OUT/c2.log | tail -3; date
# views_scaling with probe GI (issue 33's <= 1.10 at 64 views with and without GI)
timeout 100 python3 tools/pt_variants.py $OUT/c2_gi.jsonl --measures gi_views --passes --rounds 1 --frames 15 --timeout 90 base > $OUT/c2_gi.log 2>&1
grep -v -i warn $OUT/c2_gi.log | tail -1; date
# the driver's binaries of the rays benchmark's programs, BVH4 and BVH8 (tools/program_binaries.py: glGetProgramBinary per compute program)
timeout 60 python3 tools/program_binaries.py rays --scenes .scenes/tauray_test.glb --size 256x256 --bvh-layouts bvh4,bvh8 > $OUT/dumpbin.log 2>&1
tail -3 $OUT/dumpbin.log; ls $OUT/bin | wc -l; date
