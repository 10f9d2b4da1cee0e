#!/usr/bin/env bash
# Step 2 (skeletonize): the furnished synthetic room at the paper's two grid
# sizes through sg_skeletonize. threads 1: everything on one thread; 2: the
# distance transform and complex build on two (the default of the program);
# 2+par: the large collapse sub-steps too (--parallel-collapse; faster only
# when both cores are idle). SG_QUICK=1: grid A only. Wall seconds depend on
# what else runs: the load average is printed; cpu is the steadier figure.
set -euo pipefail
bench="${SG_BENCH_BIN:-build/release/bench}/skeleton_bench"
[ -x "$bench" ] || { echo "skeleton: $bench not built"; exit 0; }
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
echo
echo "| grid | threads | medium | distance s | collapse s | total s | cpu s | peak MB | nodes | edges | loops | cavities | centredness |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
"$bench" 93 205 250 1
"$bench" 93 205 250 2
"$bench" 93 205 250 2 par
if [ "${SG_QUICK:-0}" != 1 ]; then
  "$bench" 210 308 500 1
  "$bench" 210 308 500 2
  "$bench" 210 308 500 2 par
fi
echo
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
echo
echo "- targets (2-core machine): A 93x205x250 < 1.5 s; B 210x308x500 < 12 s and < 400 MB peak"
echo "- reference (Chaussard's code, 1 thread, same machine): A 3.6 s / 98 MB; B 38.5 s / 481 MB"
echo "- seconds: wall; cpu: user+system over all threads; centre: mean dist(node)/max dist in its 3x3x3"
