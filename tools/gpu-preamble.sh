# The GPU machine's setup, sourced from the repository root by tools/gpu-bench and by device call
# scripts (benchmarks/results/*/run*.sh): the GL loaders of .gl/, the wheels into /tmp/site,
# PYTHONPATH, OUT and RAYVR_COMMIT.
# GPU_BENCH_READY=1: the preamble has run (another job of the call installed /tmp/site; installing again
# under a running job would swap its modules)
if [ -z "${GPU_BENCH_READY:-}" ]; then
for f in .gl/*.deb; do dpkg -x "$f" /; done; ldconfig
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/site .whl/*.whl \
  $(ls .whlt/*.whl .whlr/*.whl .oidn/*.whl 2>/dev/null)
# .oidn/: pyoidn 2.5.1 cut to its CPU and CUDA devices (pyoidn_min.tar.xz, ~46 MB: the wheel's 88 MB do not fit
# a call's 64 MiB) with cffi and pycparser's cp312 wheels, for `targets`' OIDN timings
[ -f .oidn/pyoidn_min.tar.xz ] && tar -xJf .oidn/pyoidn_min.tar.xz -C /tmp/site
fi
export PYTHONPATH=/tmp/site:${RAYVR_SRC:-$PWD/src} PYTHONUNBUFFERED=1   # RAYVR_SRC: another tree's src (.ab/NAME/src)
OUT=${OUT:-/tmp/out}; mkdir -p "$OUT"
export RAYVR_COMMIT=${RAYVR_COMMIT:-unknown}
