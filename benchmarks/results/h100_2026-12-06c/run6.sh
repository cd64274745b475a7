#!/bin/bash
# session 19 device call 6: ReSTIR's auto target against cosine and bsdf on tauray
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1 RAYVR_COMMIT=${RAYVR_COMMIT:-wt}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT; S=.scenes
date
timeout 150 python3 -m benchmarks restir --scene $S/tauray_test.glb --parts scene --warmup 24 --error-frames 2 --frames 20 --reference-frames 96 --restir '[{"target": "auto"}, {"target": "cosine"}, {"target": "bsdf"}]' > $OUT/restir6.log 2>&1
grep -v -i warn $OUT/restir6.log | tail -12; date
cp benchmarks/results/restir.json $OUT/restir6.json 2>/dev/null
