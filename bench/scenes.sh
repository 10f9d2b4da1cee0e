# The scenes of the convergence race (bench/sections/60-convergence.sh) and
# of the comparison against the previous build (65-previous.sh), sourced by
# both, and the render options of each column.
#
# name|scene|voxel resolution (empty: the scene's own). The dark corridor
# (issue 29) is lit round two corners, where guided's learned mixture
# regressed unseen by the corridor's one corner. The staircase and
# the bathroom are their pbrt-v4 files, with their textures and microfacet
# materials; a pbrt file names no voxel size, so the bench gives the one
# their JSON stand-ins in data/external/ use. The sunlit house (issue 30) is
# lit only by a sky and a sun through one window, seen from the next room;
# the north room (issue 30) by a sky image through a north window, its sun
# (90% of the image's power) behind the house: where the openings found by
# the precompute count (section 62).
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
# shellcheck disable=SC2034
bench_modes=(bsdf skeleton guided guided-albedo openpgl)
# a column's render options: its mode, and what sets it apart
# openpgl races at its best as measured (docs/render.md, "The peer at its
# best"): the MIS mode with Open PGL's guided roulette, where the library
# has its radiance caches (make openpgl builds it so)
declare -A bench_mode_options=([guided-albedo]="--sampling guided --roulette albedo"
                               [openpgl]="--sampling openpgl --openpgl-mode mis")
options_of() { echo "${bench_mode_options[$1]:---sampling $1}"; }

# ref_field KEY FILE: the value after KEY in a reference's record, the
# ref.txt section 60 writes beside ref.exr ("relmse X mse8 Y mse Z spp N
# seconds S state T"); section 62 reads its own error from it
ref_field() { awk -v k="$1" '{for(i=1;i<NF;i++) if($i==k) print $(i+1)}' "$2"; }
