#!/usr/bin/env bash
# Step 3 (importance): build time, peak RSS and size of the importance cache
# for a synthetic scene on the paper's Sponza grid (210x308x500), with the
# targets beside them (cache < 32 MB, build < 4 s on 2 cores; the paper's
# cache took 130 MB). SG_QUICK=1: half-size grid, targets not checked.
set -euo pipefail
bench="${SG_BENCH_BIN:-build/release/bench}/importance_bench"
if [ ! -x "$bench" ]; then
  echo "importance_bench not built: $bench"
  exit 0
fi
if [ "${SG_QUICK:-0}" = "1" ]; then
  "$bench" --quick --threads 2
else
  "$bench" --threads 2
fi
