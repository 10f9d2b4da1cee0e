#!/usr/bin/env bash
# The paper's table 1 on our scenes: grid resolution, seconds of each
# precompute step, peak memory, cache size. Third-party scenes are skipped
# when ../shared/scenes is absent.
set -uo pipefail
bin=${SG_BIN:-bin}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
scenes=(
  "corridor|data/corridor/corridor.json|96"
  "cornell box|data/cornell-box/cornell-box.json|128"
  "sponza (paper's grid size)|data/external/sponza.json|500"
  "staircase (pbrt)|../shared/scenes/staircase/staircase.pbrt|256"
  "bathroom (pbrt)|../shared/scenes/bathroom/bathroom.pbrt|384"
)
[ "${SG_QUICK:-0}" = 1 ] && scenes=("${scenes[0]}" "${scenes[1]}" "sponza (quick: res 200)|data/external/sponza.json|200")

# step NAME COMMAND...: runs it, prints "seconds peakMB"
timed() { /usr/bin/time -f '%e %M' -o "$out/t" "$@" >/dev/null 2>"$out/err" || { echo "fail"; return 1; }
          awk '{printf "%.2f %.0f", $1, $2/1024}' "$out/t"; }
echo "| scene | grid@res | medium voxels | voxelize s | skeletonize s | importance s | total s | peak MB | cache MB |"
echo "|---|---|---|---|---|---|---|---|---|"
for entry in "${scenes[@]}"; do
  IFS='|' read -r name scene res <<<"$entry"
  if [ ! -e "$scene" ]; then printf '| %s | (not present: %s) | | | | | | | |\n' "$name" "$scene"; continue; fi
  v=$(timed "$bin/voxelize" "$scene" -o "$out/m.vdb" --resolution "$res") || { printf '| %s | voxelize failed: %s | | | | | | | |\n' "$name" "$(tail -1 "$out/err")"; continue; }
  grid=$(sed -nE 's/.*voxelize: ([0-9]+x[0-9]+x[0-9]+) voxels.*/\1/p' "$out/err")
  medium=$(sed -nE 's/.* medium ([0-9]+) voxels.*/\1/p' "$out/err")
  s=$(timed "$bin/skeletonize" "$out/m.vdb" -o "$out/s.ply") || { printf '| %s | skeletonize failed | | | | | | | |\n' "$name"; continue; }
  i=$(timed "$bin/importance" "$out/m.vdb" "$out/s.ply" -o "$out/c.cache") || { printf '| %s | importance failed | | | | | | | |\n' "$name"; continue; }
  read -r vs vm <<<"$v"; read -r ss sm <<<"$s"; read -r is im <<<"$i"
  total=$(awk -v a="$vs" -v b="$ss" -v c="$is" 'BEGIN{printf "%.2f", a+b+c}')
  peak=$(printf '%s\n' "$vm" "$sm" "$im" | sort -n | tail -1)
  cache=$(awk -v b="$(stat -c %s "$out/c.cache")" 'BEGIN{printf "%.1f", b/1048576}')
  printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' "$name" "$grid@$res" "$medium" "$vs" "$ss" "$is" "$total" "$peak" "$cache"
done
echo
echo "- paper, table 1: Corridor 93x205x250 13 s, 18 MB; Sponza 210x308x500 30 s, 130 MB, on a 2012 laptop"
echo "- peak MB: the largest resident set of the three steps; cache MB: importance.cache on disk"
