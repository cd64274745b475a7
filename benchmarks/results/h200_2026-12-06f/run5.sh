#!/bin/bash
# device call 5 (not run: the session's device time ran out): ReSTIR DI's visibility-hint sets on tauray (issue 31), 2x1440x1600, raw preset, every material SHADOWS:
# Shadows ms and FLIP / relMSE of 2 frames after 24 against RTShadows' 96-frame reference, as the fourth run's call 5
export RAYVR_COMMIT=${RAYVR_COMMIT:-467e658}
OUT=${OUT:-/tmp/out}; mkdir -p $OUT
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl
export PYTHONPATH=/tmp/site:$PWD/src PYTHONUNBUFFERED=1
nvidia-smi --query-gpu=name,driver_version,clocks.sm,temperature.gpu --format=csv > $OUT/gpu.txt
date
timeout 420 python3 -m benchmarks restir --scene .scenes/tauray_test.glb --parts scene --warmup 24 --error-frames 2 --frames 20 --reference-frames 96 --restir "defaults,hints,defaults hints,auto hints,lean,lean hints" > $OUT/restir5.log 2>&1
grep -v -i warn $OUT/restir5.log | tail -14; date
cp benchmarks/results/restir.json $OUT/restir5.json 2>/dev/null
