#!/bin/bash
# device call 5: combinations: A = the explicit BSDF of call 2, B = A + the leaf loop inline, base = A + the MIS branch on its side, rqold = base + the leaf loop inline
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1 RAYVR_COMMIT=${RAYVR_COMMIT:-wt}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout 540 python3 tools/pt_variants.py $OUT/c5.jsonl --measures hybrid,views --passes --rounds 2 --frames 15 --timeout 60 old A B base rqold head > $OUT/c5.log 2>&1
grep -v -i warn $OUT/c5.log | tail -3; date
