#!/usr/bin/env bash
# Scene loading: the pbrt-v4 files of the staircase and bathroom against
# their hand-made JSON versions (same PLY meshes), and Sponza's OBJ read by
# Assimp (with its uv). Target: under 1 s each,
# so that loading never dominates a step.
set -uo pipefail
bench=${SG_BENCH_BIN:-build/release/bench}
runs=5
[ "${SG_QUICK:-0}" = 1 ] && runs=2
echo "| scene | triangles | materials | warnings | seconds | target |"
echo "|---|---|---|---|---|---|"
row() { # name scene
  local name=$1 scene=$2 line
  if [ ! -e "$scene" ]; then
    printf '| %s | (scene not present: %s) | | | | |\n' "$name" "$scene"; return
  fi
  if ! line=$("$bench/scene_load" "$scene" "$runs" 2>&1); then
    printf '| %s | FAILED: %s | | | | |\n' "$name" "$line"; return
  fi
  local tris mats warns secs verdict
  tris=$(awk '{print $2}' <<<"$line"); mats=$(awk '{print $4}' <<<"$line")
  warns=$(awk '{print $8}' <<<"$line"); secs=$(awk '{print $10}' <<<"$line")
  verdict=$(awk -v t="$secs" 'BEGIN{print (t<1)?"< 1 s: ok":"< 1 s: MISSED"}')
  printf '| %s | %s | %s | %s | %s | %s |\n' "$name" "$tris" "$mats" "$warns" "$secs" "$verdict"
}
row "staircase.pbrt (774 PLY)" ../shared/scenes/staircase/staircase.pbrt
row "staircase.json (same PLY)" data/external/staircase.json
row "bathroom.pbrt (855 PLY)" ../shared/scenes/bathroom/bathroom.pbrt
row "bathroom.json (same PLY)" data/external/bathroom.json
row "sponza.json (OBJ through Assimp)" data/external/sponza.json
echo
echo "(best of $runs loads, warm file cache; build/release/bench/scene_load SCENE RUNS)"
