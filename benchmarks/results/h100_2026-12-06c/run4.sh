#!/bin/bash
# session 19 device call 2: explicit BSDF eval A/B, ReSTIR with visibility hints
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1 RAYVR_COMMIT=${RAYVR_COMMIT:-wt}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT; S=.scenes
echo "== eval A/B"; date
timeout 150 python3 tools/pt_variants.py $OUT/expl_frame.jsonl --measures hybrid,views --passes --rounds 1 --frames 15 --timeout 60 old expl base 2>&1 | grep -v -i warn | tail -6
timeout 80 python3 tools/pt_variants.py $OUT/expl_pt.jsonl --measures cornell,tauray --rounds 1 --frames 15 --timeout 30 expl base 2>&1 | grep -v -i warn | tail -4
echo "== restir scene sets (hints)"; date
timeout 200 python3 -m benchmarks restir --scene $S/tauray_test.glb --parts scene --restir "$(cat .ab/sets2.json)" 2>&1 | grep -v -i warn | tail -22
cp benchmarks/results/restir.json $OUT/restir_scene2.json; cp benchmarks/results/restir.md $OUT/restir_scene2.md
echo "== restir many (hints)"; date
timeout 170 python3 -m benchmarks restir --scene $S/tauray_test.glb --parts many --light-samples 1,2,4 --restir "$(cat .ab/sets2many.json)" 2>&1 | grep -v -i warn | tail -14
cp benchmarks/results/restir.json $OUT/restir_many2.json; cp benchmarks/results/restir.md $OUT/restir_many2.md
date
