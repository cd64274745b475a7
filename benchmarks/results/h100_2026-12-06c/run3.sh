#!/bin/bash
# session 19 device call 1: ray counting A/B, ReSTIR sets, lean stage split
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1 RAYVR_COMMIT=${RAYVR_COMMIT:-wt}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT; S=.scenes
echo "== counting A/B"; date
timeout 170 python3 tools/pt_variants.py $OUT/count_frame.jsonl --measures hybrid,views --passes --rounds 1 --frames 15 --timeout 60 old head nocount base 2>&1 | grep -v -i warn | tail -12
echo "== restir scene sets"; date
timeout 300 python3 -m benchmarks restir --scene $S/tauray_test.glb --parts scene --restir "$(cat .ab/sets1.json)" 2>&1 | grep -v -i warn | tail -30
echo "== frame_configs lean split"; date
timeout 100 python3 -m benchmarks frame_configs --scene $S/tauray_test.glb --configs "raw,raw + restir lean,raw + restir lean candidates,raw + restir lean temporal,raw + restir lean spatial" --frames 20 2>&1 | grep -v -i warn | tail -12
date
cp -r benchmarks/results/restir.* benchmarks/results/frame_configs.* $OUT/ 2>/dev/null
