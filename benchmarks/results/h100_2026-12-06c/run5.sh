#!/bin/bash
# session 19 device call 3: ReSTIR with visibility hints, timed and judged (progress in $OUT/run3.log)
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1 RAYVR_COMMIT=${RAYVR_COMMIT:-wt}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT; S=.scenes
date
timeout 60 python3 -m benchmarks frame_configs --scene $S/tauray_test.glb --configs "raw,raw + restir lean,raw + restir hints,raw + restir lean hints" --frames 20 > $OUT/fc3.log 2>&1
tail -8 $OUT/fc3.log; date
timeout 200 python3 -m benchmarks restir --scene $S/tauray_test.glb --parts scene --warmup 24 --error-frames 2 --frames 20 --reference-frames 96 --restir "$(cat .ab/sets3.json)" > $OUT/restir3.log 2>&1
grep -v -i warn $OUT/restir3.log | tail -14; date
cp benchmarks/results/restir.json $OUT/restir3.json 2>/dev/null
