#!/bin/bash
# device call 4: the suite on the GPU at 467e658, 12 pytest-xdist workers (tools/gpu-bench tests; carry .gl .whl .whlt .scenes)
RAYVR_COMMIT=${RAYVR_COMMIT:-467e658} TESTS_TIMEOUT=500 TESTS_WORKERS=12 bash tools/gpu-bench tests
