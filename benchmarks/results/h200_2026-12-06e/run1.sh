#!/bin/bash
# device call 1: bisect RTShadows' +6% over the first-parent merges 44e709f..c88eeac
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1 RAYVR_COMMIT=${RAYVR_COMMIT:-wt}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout 540 python3 tools/pt_variants.py $OUT/bisect.jsonl --measures hybrid --passes --rounds 2 --frames 15 --timeout 60 old head base t6 t5 t7 t3 t8 t1 > $OUT/bisect.log 2>&1
grep -v -i warn $OUT/bisect.log | tail -30; date
