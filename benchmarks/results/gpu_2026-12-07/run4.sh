#!/bin/bash
# device call (calls 1 and 2 in one, to spend one machine start): run1.sh's rays and trees, then run2.sh's side-by-side with Mitsuba 3
cd "$(dirname "$0")/../../.."
bash benchmarks/results/gpu_2026-12-07/run1.sh
GPU_BENCH_READY=1 bash benchmarks/results/gpu_2026-12-07/run2.sh   # the wheels are in /tmp/site already
