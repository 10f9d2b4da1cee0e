#!/usr/bin/env bash
# Voxelize speed and memory on real scenes (targets: < 3 s each for
# Sponza at 500 and the bathroom at 256 on the 2-core machine).
set -uo pipefail
bin=${SG_BIN:-bin}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
runs=3
[ "${SG_QUICK:-0}" = 1 ] && runs=1
echo "| scene | res | grid | medium voxels | seconds | peak MB | target |"
echo "|---|---|---|---|---|---|---|"
row() { # name scene resolution target_seconds
  local name=$1 scene=$2 res=$3 target=$4 best=999 mem=0 line
  if [ ! -e "$scene" ] || ! "$bin/voxelize" "$scene" --key >/dev/null 2>&1; then
    printf '| %s | %s | (scene not present: %s) | | | | |\n' "$name" "$res" "$scene"; return
  fi
  for _ in $(seq $runs); do
    line=$( { /usr/bin/time -f 'TIME %e %M' "$bin/voxelize" "$scene" -o "$out/m.vdb" --resolution "$res" --threads 2; } 2>&1 )
    local t m
    t=$(awk '/^TIME/{print $2}' <<<"$line"); m=$(awk '/^TIME/{print $3}' <<<"$line")
    best=$(awk -v a="$best" -v b="$t" 'BEGIN{print (b<a)?b:a}'); mem=$m
  done
  local grid medium verdict
  grid=$(sed -nE 's/.*voxelize: ([0-9]+x[0-9]+x[0-9]+) voxels.*/\1/p' <<<"$line")
  medium=$(sed -nE 's/.* medium ([0-9]+) voxels.*/\1/p' <<<"$line")
  verdict=$(awk -v t="$best" -v g="$target" 'BEGIN{print (t<g)?"< "g" s: ok":"< "g" s: MISSED"}')
  printf '| %s | %s | %s | %s | %.2f | %.0f | %s |\n' "$name" "$res" "$grid" "$medium" "$best" "$((mem/1024))" "$verdict"
}
row "corridor (data/)" data/corridor/corridor.json 96 3
row "cornell box (data/)" data/cornell-box/cornell-box.json 128 3
row "sponza 66k tris" data/external/sponza.json 500 3
row "bathroom 592k tris" data/external/bathroom.json 256 3
row "bathroom 592k tris" data/external/bathroom.json 384 3
row "staircase 263k tris" data/external/staircase.json 256 3
echo
echo "(best of $runs runs; seconds include loading the meshes and writing the VDB)"
