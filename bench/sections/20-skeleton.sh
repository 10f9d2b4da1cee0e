#!/usr/bin/env bash
# Step 2 (skeletonize): the furnished synthetic room at the paper's two grid
# sizes through sg_skeletonize, 2 threads (distance transform and complex
# build use them; the collapse is sequential). SG_QUICK=1: grid A only.
set -euo pipefail
bench="${SG_BENCH_BIN:-build/release/bench}/skeleton_bench"
[ -x "$bench" ] || { echo "skeleton: $bench not built"; exit 0; }
printf '%-12s %10s %8s %8s %7s %6s %7s %6s %6s %5s %4s %6s\n' \
  grid medium distance collapse total cpu peakMB nodes edges loops cav centre
"$bench" 93 205 250 2
[ "${SG_QUICK:-0}" = 1 ] || "$bench" 210 308 500 2
echo "targets (2-core machine): A 93x205x250 < 1.5 s; B 210x308x500 < 12 s and < 400 MB peak"
echo "reference (Chaussard's code, 1 thread, same machine): A 3.6 s / 98 MB; B 38.5 s / 481 MB"
echo "seconds: wall; cpu: user+system over all threads; centre: mean dist(node)/max dist in its 3x3x3"
