#!/bin/bash
# device call 4: the suite on the GPU at 8b36906, 12 pytest-xdist workers (tools/gpu-bench tests; carry .gl .whl .whlt .scenes); ran as RAYVR_COMMIT=8b36906 TESTS_TIMEOUT=380 TESTS_WORKERS=12 bash tools/gpu-bench tests
RAYVR_COMMIT=${RAYVR_COMMIT:-8b36906} TESTS_TIMEOUT=380 TESTS_WORKERS=12 bash tools/gpu-bench tests
