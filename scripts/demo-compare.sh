#!/usr/bin/env bash
# The demo's picture: the same scene rendered for the same seconds by bsdf,
# guided and (where `make openpgl` built it) openpgl, side by side with a
# long bsdf reference, each captioned with its relMSE against it.
#   scripts/demo-compare.sh SCENE CACHE OUTDIR [SECONDS] [REFERENCE_SECONDS]
# Writes OUTDIR/compare.png (and the EXRs beside it) and prints one line.
set -euo pipefail
scene=$1 cache=$2 out=$3 seconds=${4:-2} ref_seconds=${5:-30}
bin=${SG_BIN:-bin}
size=${SG_DEMO_SIZE:-240x180}
font=/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf
mkdir -p "$out"

modes=(bsdf guided)
# openpgl where this build has it (render says in one line when it has not)
if "$bin/render" "$scene" --sampling openpgl --spp 1 --size 8x6 -o "$out/probe.exr" --quiet 2>/dev/null; then
  modes+=(openpgl)
fi
rm -f "$out/probe.exr"
caption() { # IN OUT LINE1 LINE2: two lines on the image's top left, where a font is installed
  if [ -e "$font" ]; then
    oiiotool "$1" --text:x=6:y=16:size=14:color=1,1,0.4:font="$font" "$3" \
      --text:x=6:y=33:size=14:color=1,1,0.4:font="$font" "$4" -o "$2"
  else
    cp "$1" "$2"
  fi
}

# the reference: bsdf for REFERENCE_SECONDS, made once per scene and cache
key="$(sha256sum "$scene" "$cache" "$bin/render" | sha256sum | cut -c1-16) $size $ref_seconds"
if [ "$(cat "$out/reference.key" 2>/dev/null)" != "$key" ] || [ ! -e "$out/reference.exr" ]; then
  echo "demo: a ${ref_seconds} s bsdf reference of $scene" >&2
  "$bin/render" "$scene" --sampling bsdf --time "$ref_seconds" --seed 999 --size "$size" \
    -o "$out/reference.exr" --png "$out/reference.png" --quiet
  echo "$key" >"$out/reference.key"
fi

panels=() summary=()
for m in "${modes[@]}"; do
  "$bin/render" "$scene" --cache "$cache" --sampling "$m" --time "$seconds" --seed 1 --size "$size" \
    --reference "$out/reference.exr" --log "$out/$m.csv" -o "$out/$m.exr" --png "$out/$m.png" --quiet
  relmse=$(tail -1 "$out/$m.csv" | cut -d, -f4)
  spp=$(tail -1 "$out/$m.csv" | cut -d, -f2)
  caption "$out/$m.png" "$out/$m-captioned.png" "$m: $seconds s, $spp spp" "$(printf 'relMSE %.4f' "$relmse")"
  panels+=("$out/$m-captioned.png")
  summary+=("$m $(printf '%.4f' "$relmse")")
done
caption "$out/reference.png" "$out/reference-captioned.png" "reference" "bsdf, $ref_seconds s"
panels+=("$out/reference-captioned.png")
oiiotool "${panels[@]}" --mosaic:pad=4 "${#panels[@]}x1" -o "$out/compare.png"
rm -f "$out"/*-captioned.png
echo "demo: $out/compare.png: after $seconds s each, relMSE against the reference: $(IFS=,; echo "${summary[*]}" | sed 's/,/, /g')"
