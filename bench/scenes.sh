# The scenes of the convergence race (bench/sections/60-convergence.sh) and
# of the sections that build on it (portals, shards, previous build),
# sourced by each: the
# columns and their render options, the run's setting, and helpers.
#
# name|scene|voxel resolution (empty: the scene's own). The dark corridor
# is lit round two corners, where guided's learned mixture
# regressed unseen by the corridor's one corner. The staircase and
# the bathroom are their pbrt-v4 files, with their textures and microfacet
# materials; a pbrt file names no voxel size, so the bench gives the one
# their JSON stand-ins in data/external/ use. The sunlit house is
# lit only by a sky and a sun through one window, seen from the next room;
# the north room by a sky image through a north window, its sun
# (90% of the image's power) behind the house: where the openings found by
# the precompute count (the portals section, 62-portals.sh).
# shellcheck disable=SC2034
bench_scenes=(
  "corridor|data/corridor/corridor.json|"
  "dark-corridor|data/dark-corridor/dark-corridor.json|"
  "sunlit-house|data/sunlit-house/sunlit-house.json|"
  "north-room|data/north-room/north-room.json|"
  "cornell-box|data/cornell-box/cornell-box.json|"
  "sponza|data/sponza/sponza-bench.json|"
  "staircase|../shared/scenes/staircase/staircase.pbrt|256"
  "bathroom|../shared/scenes/bathroom/bathroom.pbrt|384"
)
# a column's render options: its mode, and what sets it apart
# openpgl races at its best as measured (docs/render.md, "The peer at its
# best"): the MIS mode with Open PGL's guided roulette, where the library
# has its radiance caches (make openpgl builds it so)
declare -A bench_mode_options=([guided-albedo]="--sampling guided --roulette albedo"
                               [openpgl]="--sampling openpgl --openpgl-mode mis")
options_of() { echo "${bench_mode_options[$1]:---sampling $1}"; }
# mode_of COLUMN: the sampling mode a column renders with
mode_of() { local o; read -ra o <<<"$(options_of "$1")"; echo "${o[1]}"; }

# The columns: render's sampling modes as `render --describe` lists them
# (one JSON object a line), each followed by its variants (the columns of
# bench_mode_options that render it with other options).
bench_describe=$("${bin:-bin}/render" --describe 2>/dev/null)
# mode_says MODE FIELD: whether render --describe gives MODE's FIELD as true
mode_says() { grep -F "\"name\": \"$1\"" <<<"$bench_describe" | grep -qF "\"$2\": true"; }
# shellcheck disable=SC2034
bench_modes=()
while read -r mode; do
  bench_modes+=("$mode")
  for column in $(printf '%s\n' "${!bench_mode_options[@]}" | sort); do
    [ "$column" != "$mode" ] && [ "$(mode_of "$column")" = "$mode" ] && bench_modes+=("$column")
  done
done < <(sed -nE 's/^\{"name": "([^"]+)".*/\1/p' <<<"$bench_describe")
# the baseline every column is compared with: the mode render takes
# without a precompute (plain path tracing)
# shellcheck disable=SC2034
bench_baseline=$(grep -F '"default_without_cache": true' <<<"$bench_describe" | sed -nE 's/^\{"name": "([^"]+)".*/\1/p')

# ref_field KEY FILE: the value after KEY in a reference's record, the
# ref.txt the convergence section writes beside ref.exr ("relmse X mse8 Y
# mse Z spp N seconds S state T"); the portals section reads its own error
# from it
ref_field() { awk -v k="$1" '{for(i=1;i<NF;i++) if($i==k) print $(i+1)}' "$2"; }

# The run's setting, as the convergence section chose it: quick (SG_QUICK=1), long
# (SG_LONG=1) or default, and its image size in pixels (SG_CONV_PIXELS
# overrides). by_setting QUICK LONG DEFAULT: the word for this setting.
if [ "${SG_QUICK:-0}" = 1 ]; then
  setting=quick pixels=9600
elif [ "${SG_LONG:-0}" = 1 ]; then
  setting=long pixels=921600
else
  setting=default pixels=76800
fi
pixels=${SG_CONV_PIXELS:-$pixels}
by_setting() { case $setting in quick) echo "$1" ;; long) echo "$2" ;; *) echo "$3" ;; esac; }

# bench_needs PROGRAM...: ends the section, saying why, unless bin/PROGRAM
# for each and the convergence tool are built ($bin and $tool: the
# section's).
bench_needs() {
  local p
  for p in "$@"; do
    [ -x "$bin/$p" ] || { echo "(needs $bin/$p: run make)"; exit 0; }
  done
  [ -x "$tool" ] || { echo "(needs $tool: run make bench)"; exit 0; }
}

# A section's table and notes: the rows of `rows`, then each of `notes` as
# a list item after a blank line (none: nothing).
print_rows() { for row in "${rows[@]}"; do echo "$row"; done; }
print_notes() {
  [ ${#notes[@]} -gt 0 ] || return 0
  echo
  for n in "${notes[@]}"; do echo "- $n"; done
}
