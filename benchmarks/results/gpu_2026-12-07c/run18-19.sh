#!/bin/bash
# device calls 18 and 19 (typed as the call's command on the warm machine after call 17; kept here as run):
# 18: diag15.py's workgroup variants, 10 timed frames; 19: `view_reuse` at 64 views with sources every 4th
# column and row (cut at 195 s by the session's last device seconds, before it printed a row)
cd "$(dirname "$0")/../../.."
source tools/gpu-preamble.sh; export GPU_BENCH_READY=1
if [ "${CALL:-18}" = 18 ]; then
timeout 220 python3 benchmarks/results/gpu_2026-12-07b/diag15.py .scenes/tauray_test.glb 10 $OUT/diag15.json 2>&1 \
  | grep -v -i warn | cut -c1-700 | tee $OUT/diag15.log
else
timeout 195 python3 -m benchmarks view_reuse --scene .scenes/tauray_test.glb --views 64 --out $OUT \
  --variants "Decision.source_stride=4" > $OUT/view_reuse64.log 2>&1
grep -v -i warn $OUT/view_reuse64.log | tail -7 | cut -c1-260
fi
