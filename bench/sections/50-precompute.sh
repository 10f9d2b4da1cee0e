#!/usr/bin/env bash
# The paper's table 1 on our scenes: grid resolution, seconds of each
# precompute step, peak memory, cache size; then how the precompute scales
# on Sponza (data/sponza/sponza-bench.json) at resolution 250, 500 and 1000:
# seconds and peak memory per step, and each step's growth per 8x voxels
# (targets at 1000: the three steps <= 60 s, peak <= 2 GB, growth <= 9x).
# Third-party scenes are skipped when ../shared/scenes is absent.
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

# timed COMMAND...: runs it, prints "wall-seconds peakMB CPU-seconds" (CPU: user + system)
timed() { /usr/bin/time -f '%e %M %U %S' -o "$out/t" "$@" >/dev/null 2>"$out/err" || { echo "fail"; return 1; }
          awk '{printf "%.2f %.0f %.2f", $1, $2/1024, $3 + $4}' "$out/t"; }
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
  read -r vs vm _ <<<"$v"; read -r ss sm _ <<<"$s"; read -r is im _ <<<"$i"
  total=$(awk -v a="$vs" -v b="$ss" -v c="$is" 'BEGIN{printf "%.2f", a+b+c}')
  peak=$(printf '%s\n' "$vm" "$sm" "$im" | sort -n | tail -1)
  cache=$(awk -v b="$(stat -c %s "$out/c.cache")" 'BEGIN{printf "%.1f", b/1048576}')
  printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' "$name" "$grid@$res" "$medium" "$vs" "$ss" "$is" "$total" "$peak" "$cache"
done
echo
echo "- paper, table 1: Corridor 93x205x250 13 s, 18 MB; Sponza 210x308x500 30 s, 130 MB, on a 2012 laptop"
echo "- peak MB: the largest resident set of the three steps; cache MB: importance.cache on disk"

# ---- scaling on Sponza: 250, 500, 1000 (bench-quick: 125, 250, 500) ----
sponza=data/sponza/sponza-bench.json
resolutions=(250 500 1000)
[ "${SG_QUICK:-0}" = 1 ] && resolutions=(125 250 500)
[ -n "${SG_SCALING_RESOLUTIONS:-}" ] && read -ra resolutions <<<"$SG_SCALING_RESOLUTIONS" # e.g. "40 80 160"
echo
if [ ! -e "$(dirname "$sponza")/$(sed -nE 's/.*"mesh": *"([^"]*)".*/\1/p' "$sponza")" ]; then
  echo "(scaling on Sponza skipped: its mesh, ../shared/scenes/sponza-dabrovic, is not present)"
  exit 0
fi
echo "Scaling on Sponza ($sponza), every core; seconds wall (CPU seconds in brackets), peak resident MB per step:"
echo
echo "| resolution | grid | medium voxels | voxelize s | skeletonize s | importance s | total s | peak MB (vox / skel / imp) | cache MB | load |"
echo "|---|---|---|---|---|---|---|---|---|---|"
declare -A wall
prev=""
for res in "${resolutions[@]}"; do
  load=$(cut -d' ' -f1 /proc/loadavg)
  v=$(timed "$bin/voxelize" "$sponza" -o "$out/m.vdb" --resolution "$res") || { echo "| $res | voxelize failed: $(tail -1 "$out/err") | | | | | | | | |"; continue; }
  grid=$(sed -nE 's/.*voxelize: ([0-9]+x[0-9]+x[0-9]+) voxels.*/\1/p' "$out/err")
  medium=$(sed -nE 's/.* medium ([0-9]+) voxels.*/\1/p' "$out/err")
  s=$(timed "$bin/skeletonize" "$out/m.vdb" -o "$out/s.ply") || { echo "| $res | skeletonize failed | | | | | | | | |"; continue; }
  i=$(timed "$bin/importance" "$out/m.vdb" "$out/s.ply" -o "$out/c.cache") || { echo "| $res | importance failed | | | | | | | | |"; continue; }
  read -r vs vm vu <<<"$v"; read -r ss sm su <<<"$s"; read -r is im iu <<<"$i"
  total=$(awk -v a="$vs" -v b="$ss" -v c="$is" 'BEGIN{printf "%.2f", a+b+c}')
  cache=$(awk -v b="$(stat -c %s "$out/c.cache")" 'BEGIN{printf "%.1f", b/1048576}')
  printf '| %s | %s | %s | %s (%s) | %s (%s) | %s (%s) | %s | %s / %s / %s | %s | %s |\n' "$res" "$grid" "$medium" \
    "$vs" "$vu" "$ss" "$su" "$is" "$iu" "$total" "$vm" "$sm" "$im" "$cache" "$load"
  wall[$res]="$vs $ss $is $total $medium"
  rm -f "$out/m.vdb" "$out/s.ply" "$out/c.cache"
done
echo
growth() { # growth A B: step times at B over A, per 8x voxels (medium ratio / 8 scales it)
  read -r av as ai at am <<<"${wall[$1]:-}"; read -r bv bs bi bt bm <<<"${wall[$2]:-}"
  [ -n "${at:-}" ] && [ -n "${bt:-}" ] || return 0
  awk -v av="$av" -v as="$as" -v ai="$ai" -v at="$at" -v bv="$bv" -v bs="$bs" -v bi="$bi" -v bt="$bt" \
      -v am="$am" -v bm="$bm" -v a="$1" -v b="$2" 'BEGIN{
    printf "| %s -> %s | %.2fx | %.1fx | %.1fx | %.1fx | %.1fx |\n", a, b, bm / am, bv / av, bs / as, bi / ai, bt / at }'
}
echo "| growth | medium voxels | voxelize | skeletonize | importance | total |"
echo "|---|---|---|---|---|---|"
growth "${resolutions[0]}" "${resolutions[1]}"
growth "${resolutions[1]}" "${resolutions[2]}"
echo
echo "- targets at 1000 (make bench on an idle 2-core machine): total <= 60 s, every peak <= 2048 MB, each step's time <= 9x from 500 to 1000"
echo "- load: the 1-minute load average when the row started; wall seconds are only comparable on an idle machine, CPU seconds less sensitive to it"
