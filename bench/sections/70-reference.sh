#!/usr/bin/env bash
# Against an independent renderer: the staircase and the bathroom as their
# pbrt-v4 files describe them (textures, microfacet materials), rendered
# with BSDF sampling until the means have settled, against Tungsten's
# converged images of the original scenes (../shared/scenes/*/
# TungstenRender.exr), box-filtered down to our size. Compared on the
# pixels whose first surface has all its textures (bench/reference_compare.c);
# the whole image's ratio is given too. Target: every channel's mean within
# 5 % of Tungsten's on those pixels. bench/README.md, "Checked against Tungsten",
# says what differs and why.
set -uo pipefail
bin=${SG_BIN:-bin}
compare=${SG_BENCH_BIN:-build/release/bench}/reference_compare
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
seconds=120
[ "${SG_QUICK:-0}" = 1 ] && seconds=20
[ "${SG_LONG:-0}" = 1 ] && seconds=600
report_dir=${SG_REPORT_DIR:-}

echo "| scene | size | spp | masked pixels | ours / Tungsten, masked (R G B) | whole image (R G B) | worst 1/16 region | target |"
echo "|---|---|---|---|---|---|---|---|"
row() { # name scene size
  local name=$1 scene=$2 size=$3 ref line spp mask masked all worst verdict
  ref=$(dirname "$scene")/TungstenRender.exr
  if [ ! -e "$scene" ] || [ ! -e "$ref" ]; then
    printf '| %s | (scene or reference not present: %s) | | | | | | |\n' "$name" "$scene"; return
  fi
  if ! line=$("$bin/render" "$scene" --sampling bsdf --max-depth 32 --size "$size" --time "$seconds" \
                -o "$out/$name.exr" 2>&1); then
    printf '| %s | FAILED: %s | | | | | | |\n' "$name" "$(tail -1 <<<"$line")"; return
  fi
  spp=$(sed -nE 's/.* ([0-9]+) spp,.*/\1/p' <<<"$line" | tail -1)
  if ! line=$("$compare" "$scene" "$out/$name.exr" "$ref" 2>&1); then
    printf '| %s | FAILED: %s | | | | | | |\n' "$name" "$line"; return
  fi
  mask=$(awk '/^mask/{printf "%.0f %%", 100*$2}' <<<"$line")
  masked=$(awk '/^ratio_masked/{printf "%.3f %.3f %.3f", $2, $3, $4}' <<<"$line")
  all=$(awk '/^ratio_all/{printf "%.3f %.3f %.3f", $2, $3, $4}' <<<"$line")
  worst=$(awk '/^worst_region/{printf "%.3f", $2}' <<<"$line")
  verdict=$(awk '/^ratio_masked/{ok=1; for(i=2;i<=4;i++) if ($i<0.95||$i>1.05) ok=0; print ok?"within 5 %: ok":"within 5 %: MISSED"}' <<<"$line")
  printf '| %s | %s | %s | %s | %s | %s | %s | %s |\n' "$name" "$size" "$spp" "$mask" "$masked" "$all" "$worst" "$verdict"
  if [ -n "$report_dir" ]; then
    mkdir -p "$report_dir"
    oiiotool "$out/$name.exr" --colorconvert linear sRGB -o "$report_dir/reference-$name-ours.png" >/dev/null 2>&1
    oiiotool "$ref" --resize "$size" --colorconvert linear sRGB -o "$report_dir/reference-$name-tungsten.png" \
      >/dev/null 2>&1
  fi
}
row staircase ../shared/scenes/staircase/staircase.pbrt 180x320
row bathroom ../shared/scenes/bathroom/bathroom.pbrt 256x256
if [ -n "$report_dir" ] && [ -e "$report_dir/reference-staircase-ours.png" ]; then
  link=${SG_REPORT_LINK:-$report_dir}
  echo
  for name in staircase bathroom; do
    [ -e "$report_dir/reference-$name-ours.png" ] &&
      echo "**$name**, ours (left) and Tungsten's: ![ours]($link/reference-$name-ours.png) ![Tungsten]($link/reference-$name-tungsten.png)"
  done
fi
echo
echo "($seconds s of bsdf sampling per scene, all cores, path length 32; masked: the camera ray's first"
echo "surface has every texture it names; build/release/bench/reference_compare SCENE OURS.exr TUNGSTEN.exr)"
