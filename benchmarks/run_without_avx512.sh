#!/usr/bin/env bash
# Run a command with the numba kernels compiled for Zen 2 without AVX-512 and OpenBLAS's Zen
# kernels, to see what a machine without AVX-512 would do (issue 26, RESULTS_bounds_realizations:
# crack 2000 i = 11).  The kernels are warmed first (numba caches them per CPU name and features).
#
#   benchmarks/run_without_avx512.sh python3 benchmarks/bench_bounds_realizations.py \
#       --one crack 2000 11 --no-check
set -euo pipefail
cd "$(dirname "$0")/.."
features=$(python3 -c "
import llvmlite.binding as ll
print(','.join(f.replace('+avx512', '-avx512') for f in ll.get_host_cpu_features().flatten().split(',')))")
export NUMBA_CPU_NAME=znver2 NUMBA_CPU_FEATURES="$features" OPENBLAS_CORETYPE=Zen
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 NUMBA_NUM_THREADS=1
python3 -c "import sys; sys.path.insert(0, 'tests'); import warm_kernels; warm_kernels.bounds_kernels()" >/dev/null
exec "$@"
