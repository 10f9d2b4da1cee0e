#!/usr/bin/env bash
# Convergence: the paper's table 2 on our scenes. For each scene, the
# precompute (voxelize, skeletonize, importance) and a bsdf reference made of
# two independent halves, both kept in bench/out/NAME/ and remade only when
# what they depend on changes; then `bsdf`, `skeleton` and `guided` for a
# fixed time each, with several seeds, modes interleaved within each seed,
# every run logging its error curve against the reference. bench/convergence
# (bench/convergence.c) averages the curves over seeds and writes the tables;
# gnuplot draws relMSE against time; `convergence strip` makes the
# equal-time crops. Settings: SG_QUICK=1 (a first look), default, SG_LONG=1
# (publication). Overrides: SG_CONV_SECONDS, SG_CONV_SEEDS, SG_CONV_PIXELS,
# SG_REF_SECONDS (seconds of each reference half), SG_CONV_SCENES (names,
# space-separated), SG_KEEP_REFERENCES=1 (keep references made by another
# build of bin/render). Images go to SG_REPORT_DIR, linked as SG_REPORT_LINK;
# the headline rows to SG_HEADLINE_FILE (both set by bench/run.sh).
set -uo pipefail
bin=${SG_BIN:-bin}
tool=${SG_BENCH_BIN:-build/release/bench}/convergence

# Bump when the references' recipe changes (it is part of their key).
REFERENCE_VERSION=1

if [ "${SG_QUICK:-0}" = 1 ]; then
  setting=quick pixels=9600 seconds=4 seeds=1 ref_seconds=15
elif [ "${SG_LONG:-0}" = 1 ]; then
  setting=long pixels=76800 seconds=60 seeds=5 ref_seconds=600
else
  setting=default pixels=19200 seconds=12 seeds=3 ref_seconds=60
fi
pixels=${SG_CONV_PIXELS:-$pixels}
seconds=${SG_CONV_SECONDS:-$seconds}
seeds=${SG_CONV_SEEDS:-$seeds}
ref_seconds=${SG_REF_SECONDS:-$ref_seconds}
report_dir=${SG_REPORT_DIR:-bench/out/report-$setting}
report_link=${SG_REPORT_LINK:-$report_dir}
mkdir -p "$report_dir"

scenes=(
  "corridor|data/corridor/corridor.json"
  "cornell-box|data/cornell-box/cornell-box.json"
  "sponza|data/sponza/sponza-bench.json"
  "staircase|data/external/staircase.json"
  "bathroom|data/external/bathroom.json"
)
modes=(bsdf skeleton guided)

note() { [ -t 2 ] && printf '\r\033[Kconvergence: %s' "$*" >&2; return 0; }
for p in voxelize skeletonize importance render; do
  [ -x "$bin/$p" ] || { echo "(needs $bin/$p: run make)"; exit 0; }
done
[ -x "$tool" ] || { echo "(needs $tool: run make bench)"; exit 0; }

tables=$(mktemp -d)
trap 'rm -rf "$tables"' EXIT
notes=()

# precompute NAME SCENE DIR: the three steps into DIR, only when the
# geometry key changed, an output is missing or a step's program is newer.
precompute() {
  local name=$1 scene=$2 dir=$3 key
  mkdir -p "$dir"
  key=$("$bin/voxelize" "$scene" --key 2>&1) || { notes+=("$name: voxelize --key failed: $key"); return 1; }
  local stale=0
  [ "$key" = "$(cat "$dir/geometry.key" 2>/dev/null)" ] || stale=1
  for f in medium.vdb skeleton.ply importance.cache; do [ -e "$dir/$f" ] || stale=1; done
  for p in voxelize skeletonize importance; do [ "$bin/$p" -nt "$dir/importance.cache" ] && stale=1; done
  [ $stale = 0 ] && return 0
  note "$name: precompute"
  rm -f "$dir/geometry.key"
  "$bin/voxelize" "$scene" -o "$dir/medium.vdb" >"$dir/precompute.log" 2>&1 &&
  "$bin/skeletonize" "$dir/medium.vdb" -o "$dir/skeleton.ply" >>"$dir/precompute.log" 2>&1 &&
  "$bin/importance" "$dir/medium.vdb" "$dir/skeleton.ply" -o "$dir/importance.cache" >>"$dir/precompute.log" 2>&1 ||
    { notes+=("$name: precompute failed: $(tail -1 "$dir/precompute.log")"); return 1; }
  printf '%s\n' "$key" >"$dir/geometry.key"
}

# reference NAME SCENE DIR SIZE EXPOSURE: DIR/ref.exr and DIR/ref.txt
# ("relmse X mse8 Y spp N seconds S state T"), remade when the key changes.
reference() {
  local name=$1 scene=$2 dir=$3 size=$4 exposure=$5 key render_id
  mkdir -p "$dir"
  # the render build is part of the key: a renderer that changed may
  # converge to another image (SG_KEEP_REFERENCES=1 trusts it did not)
  render_id=$(sha256sum "$bin/render" | cut -c1-16)
  key="version $REFERENCE_VERSION; $(cat "$dir/../geometry.key"); scene $(sha256sum "$scene" | cut -c1-16);"
  key+=" size $size; half $ref_seconds s"
  local old
  old=$(cat "$dir/ref.key" 2>/dev/null)
  [ "${SG_KEEP_REFERENCES:-0}" = 1 ] && old=${old%; render *}
  [ "${SG_KEEP_REFERENCES:-0}" = 1 ] || key+="; render $render_id"
  if [ -e "$dir/ref.exr" ] && [ -e "$dir/ref.txt" ] && [ "$key" = "$old" ]; then
    sed -i 's/ state .*/ state kept/' "$dir/ref.txt"
    return 0
  fi
  key="${key%; render *}; render $render_id"
  note "$name: reference, 2 x $ref_seconds s"
  rm -f "$dir/ref.key"
  local line spp t0 t1 stats
  t0=$(date +%s)
  line=$("$bin/render" "$scene" --sampling bsdf --time "$ref_seconds" --seed 1001 --size "$size" \
           -o "$dir/half-a.exr" 2>&1) || { notes+=("$name: reference failed: $line"); return 1; }
  spp=$(sed -nE 's/.* ([0-9]+) spp,.*/\1/p' <<<"$line" | tail -1)
  [ -n "$spp" ] || { notes+=("$name: reference: no spp in: $line"); return 1; }
  line=$("$bin/render" "$scene" --sampling bsdf --spp "$spp" --seed 1002 --size "$size" \
           -o "$dir/half-b.exr" 2>&1) || { notes+=("$name: reference failed: $line"); return 1; }
  stats=$("$tool" reference "$dir/half-a.exr" "$dir/half-b.exr" -o "$dir/ref.exr" --exposure "$exposure" 2>&1) ||
    { notes+=("$name: $stats"); return 1; }
  t1=$(date +%s)
  printf '%s spp %s seconds %s state made\n' "$stats" "$((2 * spp))" "$((t1 - t0))" >"$dir/ref.txt"
  printf '%s\n' "$key" >"$dir/ref.key"
}

field() { awk -v k="$1" '{for(i=1;i<NF;i++) if($i==k) print $(i+1)}' "$2"; }

plot() { # name dir size levels-file ref-relmse png
  local name=$1 dir=$2 size=$3 ref_rel=$5 png=$6 l1 l2
  read -r _ l1 l2 _ <"$4"
  gnuplot 2>"$dir/gnuplot.log" <<EOF || notes+=("$name: gnuplot failed: $(tail -1 "$dir/gnuplot.log")")
set terminal pngcairo size 560,400 font ",9"
set output "$png.tmp"
set logscale xy
set format y "%.0e"
set grid xtics ytics mxtics mytics lc rgb "#dddddd"
set xlabel "seconds of rendering"
set ylabel "relMSE against the reference"
set title "$name, ${size}: mean of $seeds seed(s)"
set key outside below horizontal maxrows 2 width 1
plot "$dir/runs/bsdf.mean.dat" u 1:3 w l lw 2 lc rgb "#1f77b4" t "bsdf", \
     "$dir/runs/skeleton.mean.dat" u 1:3 w l lw 2 lc rgb "#ff7f0e" t "skeleton (biased)", \
     "$dir/runs/guided.mean.dat" u 1:3 w l lw 2 lc rgb "#2ca02c" t "guided", \
     $ref_rel w l dt 2 lw 1.5 lc rgb "#7f7f7f" t "reference's own error", \
     $l1 w l dt 3 lc rgb "#000000" t "table 2 levels", \
     $l2 w l dt 3 lc rgb "#000000" notitle
EOF
  [ -s "$png.tmp" ] && mv "$png.tmp" "$png"
  rm -f "$png.tmp"
}

have_gnuplot=1
command -v gnuplot >/dev/null || have_gnuplot=0
figures=()
for entry in "${scenes[@]}"; do
  IFS='|' read -r name scene <<<"$entry"
  if [ -n "${SG_CONV_SCENES:-}" ] && [[ " $SG_CONV_SCENES " != *" $name "* ]]; then continue; fi
  if [ ! -e "$scene" ] || ! "$bin/voxelize" "$scene" --key >/dev/null 2>&1; then
    notes+=("$name: skipped, its scene or meshes are not present ($scene; third-party scenes live in ../shared/scenes)")
    continue
  fi
  dir=bench/out/$name
  precompute "$name" "$scene" "$dir" || continue
  read -r size exposure < <("$tool" size "$scene" "$pixels") || { notes+=("$name: cannot read the scene"); continue; }
  refdir=$dir/ref-$setting
  reference "$name" "$scene" "$refdir" "$size" "$exposure" || continue
  runs=$dir/runs
  rm -rf "$runs"; mkdir -p "$runs"
  for seed in $(seq "$seeds"); do
    # modes interleaved, the order rotated per seed: load changes hit all alike
    for k in 0 1 2; do
      mode=${modes[$(((k + seed - 1) % 3))]}
      note "$name: $mode, seed $seed/$seeds, $seconds s"
      "$bin/render" "$scene" --cache "$dir/importance.cache" --sampling "$mode" --time "$seconds" \
        --seed "$seed" --size "$size" --reference "$refdir/ref.exr" --log "$runs/$mode-$seed.csv" \
        -o "$runs/$mode-$seed.exr" --quiet 2>"$runs/$mode-$seed.err" ||
        notes+=("$name: $mode seed $seed failed: $(tail -1 "$runs/$mode-$seed.err")")
    done
  done
  "$tool" analyze "$name" "$runs" "$seeds" "$tables" --size "$size" \
    --ref-relmse "$(field relmse "$refdir/ref.txt")" --ref-mse8 "$(field mse8 "$refdir/ref.txt")" \
    --ref-spp "$(field spp "$refdir/ref.txt")" --ref-seconds "$(field seconds "$refdir/ref.txt")" \
    --ref-state "$(field state "$refdir/ref.txt")" 2>"$runs/analyze.err" ||
    { notes+=("$name: analyze failed: $(tail -1 "$runs/analyze.err")"); continue; }
  fig="![$name: relMSE against time]($report_link/$name-convergence.png)"
  if [ $have_gnuplot = 1 ]; then
    plot "$name" "$dir" "$size" "$runs/levels.txt" "$(field relmse "$refdir/ref.txt")" "$report_dir/$name-convergence.png"
  else
    fig="(no plot: gnuplot is not installed; make bench-deps installs it)"
  fi
  crop=$("$tool" strip "$refdir/ref.exr" --exposure "$exposure" -o "$report_dir/$name-crops.png" \
           "$runs/bsdf-1.exr" "$runs/skeleton-1.exr" "$runs/guided-1.exr" 2>&1) ||
    notes+=("$name: crops failed: $crop")
  figures+=("**$name** ($size, exposure $exposure): relMSE against time; equal-time crops after $seconds s (seed 1), left to right bsdf, skeleton, guided, reference, ${crop#crop } (x,y,w,h: the square where bsdf's relative error is largest)"
            "$fig ![$name: equal-time crops]($report_link/$name-crops.png)")
done
note "done"; [ -t 2 ] && printf '\n' >&2

echo "Setting **$setting**: each scene's image scaled to about $pixels pixels (aspect kept); every run"
echo "$seconds s of rendering (\`render --time\`: scene loading, BVH and guide set-up excluded); $seeds seed(s) per"
echo "mode, modes interleaved within a seed; curves averaged over seeds on a common time grid (log-log"
echo "interpolation). References: \`render --sampling bsdf\`, two halves of the same spp (seeds 1001, 1002,"
echo "the first $ref_seconds s long) averaged; their own error is estimated from the halves' difference."
echo
echo "### References"
echo
echo "| scene | size | spp | seconds | own relMSE / mse8 | lowest level relMSE / mse8 | own / level (worst) | verdict | this run |"
echo "|---|---|---|---|---|---|---|---|---|"
cat "$tables/reference.md" 2>/dev/null
echo
echo "An error measured against the reference is the run's own error plus the reference's (they are"
echo "independent): a curve cannot go below the reference's own error, drawn dashed in the plots."
echo
echo "### Table 2: seconds to reach a relMSE level"
echo
echo "relMSE = mean over pixels and channels of (x - ref)^2 / (ref^2 + 0.01), on the linear image times"
echo "2^exposure (the scene's PNG exposure), so that dark scenes are measured relatively too."
echo "Levels per scene from bsdf alone, the same for every mode: bsdf's mean error at the end of its run"
echo "and at an eighth of it, rounded up to two digits. Speed-up = bsdf seconds / mode"
echo "seconds (> 1: faster than bsdf). ~: extrapolated along 1/t from the last half of the curve;"
echo "< t: already below at the first pass; never: not reached and the curve too flat to extrapolate"
echo "(log-log slope above -0.5: a biased mode stuck on its bias)."
echo
echo "| scene | relMSE level | bsdf s | skeleton s | guided s | skeleton speed-up | guided speed-up |"
echo "|---|---|---|---|---|---|---|"
cat "$tables/table2-relmse.md" 2>/dev/null
echo
echo "### Table 2: seconds to reach an 8-bit MSE level (the paper's measure)"
echo
echo "mse8 = mean squared difference of the 8-bit sRGB values of the PNG at the scene's exposure (the"
echo "paper's MSE 100 and 40 were at its own exposures and image sizes). Same rules as above."
echo
echo "| scene | mse8 level | bsdf s | skeleton s | guided s | skeleton speed-up | guided speed-up |"
echo "|---|---|---|---|---|---|---|"
cat "$tables/table2-mse8.md" 2>/dev/null
echo
echo "### Equal time"
echo
echo "Errors of the mean curves at the time every mode reached; ratio = bsdf error / mode error (for"
echo "unbiased modes, the speed-up); µs/sample: wall time per path over both cores."
echo
echo "| scene | size | seconds | spp bsdf / skeleton / guided | µs/sample bsdf / skel. / guided | relMSE bsdf | skeleton | guided | ratio skel. / guided | mse8 bsdf | skeleton | guided | ratio skel. / guided |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
cat "$tables/equal-time.md" 2>/dev/null
echo
echo "### Plots and equal-time crops"
echo
for line in "${figures[@]}"; do printf '%s\n\n' "$line"; done
if [ ${#notes[@]} -gt 0 ]; then
  echo "### Notes"
  echo
  for n in "${notes[@]}"; do echo "- $n"; done
  echo
fi
[ -n "${SG_HEADLINE_FILE:-}" ] && cp "$tables/headline.tsv" "$SG_HEADLINE_FILE" 2>/dev/null
echo "Load average at the end of the section: $(cut -d' ' -f1-3 /proc/loadavg)."
exit 0
