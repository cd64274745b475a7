#!/bin/bash
# device call 4: the explicit BSDF with the MIS branch on its side (base) against 44e709f (old); base without ray counting in RTShadows/RTReflections (nocount) and with the leaf loop inline (rqold)
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1 RAYVR_COMMIT=${RAYVR_COMMIT:-wt}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout 540 python3 tools/pt_variants.py $OUT/c4.jsonl --measures hybrid --passes --rounds 2 --frames 15 --timeout 60 old base nocount rqold head > $OUT/c4.log 2>&1
grep -v -i warn $OUT/c4.log | tail -3; date
