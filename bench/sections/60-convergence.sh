#!/usr/bin/env bash
# Convergence: the paper's table 2 on our scenes, as a fair race. For each
# scene, the precompute (voxelize, skeletonize, importance) and a bsdf
# reference made of two independent halves, both kept in bench/out/NAME/ and
# remade only when what they depend on changes; then each learned mode's
# training, alone (render --field-out: guided, guided with the albedo
# roulette, and openpgl, Open PGL the peer, left out and said in the notes
# when this build of render has no Open PGL), timed; then `bsdf`,
# `skeleton`, `guided`, `guided-albedo` (guided --roulette albedo: the guide
# judged apart from the learned roulette) and `openpgl`, the learned ones
# from their stored field (render --field: nothing learned on the clock),
# for a fixed time each, with several seeds, modes interleaved within each
# seed, every run logging its error curve against the reference. The
# preparation (precompute, training) is tabled, and time-to-error is given
# twice: rendering alone, and with each mode's preparation added. bench/convergence (bench/convergence.c)
# averages the curves over seeds and writes the tables (relMSE, 8-bit MSE
# and linear MSE); gnuplot draws relMSE and MSE against time; `convergence
# strip` makes the equal-time crops. Settings: SG_QUICK=1 (a first look), default, SG_LONG=1
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

# the scenes, the columns' options and the setting (shared with 62, 64, 65)
source bench/scenes.sh
source bench/precompute_steps.sh
scenes=("${bench_scenes[@]}")
modes=("${bench_modes[@]}")

seconds=${SG_CONV_SECONDS:-$(by_setting 4 240 20)}
seeds=${SG_CONV_SEEDS:-$(by_setting 1 3 3)}
ref_seconds=${SG_REF_SECONDS:-$(by_setting 15 1800 120)}
report_dir=${SG_REPORT_DIR:-bench/out/report-$setting}
report_link=${SG_REPORT_LINK:-$report_dir}
mkdir -p "$report_dir"

note() { [ -t 2 ] && printf '\r\033[Kconvergence: %s' "$*" >&2; return 0; }
bench_needs voxelize skeletonize importance render

tables=$(mktemp -d)
trap 'rm -rf "$tables"' EXIT
notes=()

# The peer is in only where render was built with Open PGL (make openpgl;
# make bench builds it first): one pixel of the corridor tells.
if ! probe=$("$bin/render" data/corridor/corridor.json --sampling openpgl --spp 1 --size 4x3 \
               -o "$tables/probe.exr" --quiet 2>&1); then
  mapfile -t modes < <(for column in "${modes[@]}"; do [ "$(mode_of "$column")" != openpgl ] && echo "$column"; done)
  notes+=("openpgl: not run, this build of render cannot: ${probe##*$'\n'} (make bench builds the peer first with scripts/build-openpgl.sh; it needs ../shared/peers/openpgl-0.7.1.tar.gz)")
fi
rm -f "$tables/probe.exr"
mode_list=$(IFS=,; echo "${modes[*]}")

# precompute NAME SCENE DIR [RESOLUTION]: the three steps into DIR, only
# when the geometry key changed, an output is missing or a step's program
# is newer.
precompute() {
  local name=$1 scene=$2 dir=$3 key res=()
  [ -n "${4:-}" ] && res=(--resolution "$4")
  mkdir -p "$dir"
  key=$("$bin/voxelize" "$scene" "${res[@]}" --key 2>&1) || { notes+=("$name: voxelize --key failed: $key"); return 1; }
  local stale=0
  [ "$key" = "$(cat "$dir/geometry.key" 2>/dev/null)" ] || stale=1
  for f in medium.vdb skeleton.ply importance.cache precompute.ns; do [ -e "$dir/$f" ] || stale=1; done
  for p in voxelize skeletonize importance; do [ "$bin/$p" -nt "$dir/importance.cache" ] && stale=1; done
  [ $stale = 0 ] && return 0
  note "$name: precompute"
  rm -f "$dir/geometry.key"
  local t0
  t0=$(date +%s%N)
  precompute_steps "$bin" "$scene" "$dir" "${4:-}" ||
    { notes+=("$name: precompute failed: $(tail -1 "$dir/precompute.log")"); return 1; }
  printf '%s\n' "$key" >"$dir/geometry.key"
  printf '%s\n' "$(( $(date +%s%N) - t0 ))" >"$dir/precompute.ns"
}

# train NAME SCENE DIR SIZE MODE: MODE's field, DIR/fields-SIZE/MODE.field,
# and the seconds its training took (its passes, as render counts a run's
# time) in MODE.seconds; remade when the cache or render changed
train() {
  local name=$1 scene=$2 dir=$3 size=$4 mode=$5 fdir=$3/fields-$4 line
  mkdir -p "$fdir"
  if [ -e "$fdir/$mode.field" ] && [ -e "$fdir/$mode.seconds" ] && [ "$fdir/$mode.field" -nt "$bin/render" ] &&
     [ "$fdir/$mode.field" -nt "$dir/importance.cache" ]; then
    return 0
  fi
  note "$name: $mode, training"
  # shellcheck disable=SC2046
  line=$("$bin/render" "$scene" --cache "$dir/importance.cache" $(options_of "$mode") --seed 999 --size "$size" \
           --field-out "$fdir/$mode.field" -o "$fdir/$mode-training.exr" 2>&1) ||
    { notes+=("$name: $mode training failed: ${line##*$'\n'}"); return 1; }
  sed -nE 's/.* spp, ([0-9.]+) s,.*/\1/p' <<<"$line" | tail -1 >"$fdir/$mode.seconds"
}

# reference NAME SCENE DIR SIZE EXPOSURE: DIR/ref.exr and DIR/ref.txt
# ("relmse X mse8 Y mse Z spp N seconds S state T"), remade when the key
# changes.
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
    # a reference made before the linear MSE was measured: its halves tell
    if [ -z "$(ref_field mse "$dir/ref.txt")" ] && [ -e "$dir/half-a.exr" ] && [ -e "$dir/half-b.exr" ]; then
      local s
      if s=$("$tool" reference "$dir/half-a.exr" "$dir/half-b.exr" -o "$dir/ref.check.exr" --exposure "$exposure" 2>&1); then
        printf '%s spp %s seconds %s state kept\n' "$s" "$(ref_field spp "$dir/ref.txt")" \
          "$(ref_field seconds "$dir/ref.txt")" >"$dir/ref.txt"
      fi
      rm -f "$dir/ref.check.exr"
    fi
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

declare -A color=([bsdf]="#1f77b4" [skeleton]="#ff7f0e" [guided]="#2ca02c" [guided-albedo]="#8c564b"
                  [openpgl]="#d62728")
declare -A label=([skeleton]="skeleton (biased)")

# panel DIR COLUMN YLABEL REF-ERROR LEVEL1 LEVEL2: the gnuplot commands of
# one panel: every mode's mean curve (COLUMN of DIR/runs/MODE.mean.dat), the
# reference's own error (when known) and the two table 2 levels
panel() {
  local dir=$1 col=$2 ylabel=$3 ref=$4 l1=$5 l2=$6 m items=()
  for m in "${modes[@]}"; do
    [ -s "$dir/runs/$m.mean.dat" ] || continue
    items+=("\"$dir/runs/$m.mean.dat\" u 1:$col w l lw 2 lc rgb \"${color[$m]:-#9467bd}\" t \"${label[$m]:-$m}\"")
  done
  [ -n "$ref" ] && items+=("$ref w l dt 2 lw 1.5 lc rgb \"#7f7f7f\" t \"reference's own error\"")
  items+=("$l1 w l dt 3 lc rgb \"#000000\" t \"table 2 levels\"" "$l2 w l dt 3 lc rgb \"#000000\" notitle")
  echo "set ylabel \"$ylabel\""
  local IFS=,
  echo "plot ${items[*]}"
}

plot() { # name dir size levels-file ref-relmse ref-mse png
  local name=$1 dir=$2 size=$3 ref_rel=$5 ref_mse=$6 png=$7 r1 r2 m1 m2
  read -r _ r1 r2 _ _ _ _ m1 m2 <"$4"
  gnuplot 2>"$dir/gnuplot.log" <<EOF || notes+=("$name: gnuplot failed: $(tail -1 "$dir/gnuplot.log")")
set terminal pngcairo size 960,440 font ",9"
set output "$png.tmp"
set logscale xy
set format y "%.0e"
set grid xtics ytics mxtics mytics lc rgb "#dddddd"
set xlabel "seconds of rendering"
set key outside below horizontal maxcols 3 maxrows 3 samplen 2
set multiplot layout 1,2 title "$name, ${size}: mean of $seeds seed(s)"
$(panel "$dir" 3 "relMSE against the reference" "$ref_rel" "$r1" "$r2")
$(panel "$dir" 5 "linear-radiance MSE against the reference" "$ref_mse" "$m1" "$m2")
unset multiplot
EOF
  [ -s "$png.tmp" ] && mv "$png.tmp" "$png"
  rm -f "$png.tmp"
}

have_gnuplot=1
command -v gnuplot >/dev/null || have_gnuplot=0
figures=()
for entry in "${scenes[@]}"; do
  IFS='|' read -r name scene resolution <<<"$entry"
  if [ -n "${SG_CONV_SCENES:-}" ] && [[ " $SG_CONV_SCENES " != *" $name "* ]]; then continue; fi
  if [ ! -e "$scene" ] || ! "$bin/voxelize" "$scene" --key >/dev/null 2>&1; then
    notes+=("$name: skipped, its scene or meshes are not present ($scene; third-party scenes live in ../shared/scenes)")
    continue
  fi
  dir=bench/out/$name
  precompute "$name" "$scene" "$dir" "$resolution" || continue
  read -r size exposure < <("$tool" size "$scene" "$pixels") || { notes+=("$name: cannot read the scene"); continue; }
  refdir=$dir/ref-$setting
  reference "$name" "$scene" "$refdir" "$size" "$exposure" || continue
  # each learned mode's training, alone and timed; its preparation
  # (seconds): the precompute for the modes that read the cache, and its
  # own training
  declare -A field_of=() prep_of=()
  pre_s=$(awk '{printf "%.2f", $1 / 1e9}' "$dir/precompute.ns" 2>/dev/null)
  for mode in "${modes[@]}"; do
    read -r _ m_sampling _ <<<"$(options_of "$mode")"
    desc=$("$bin/render" --describe "$m_sampling")
    prep=0 train_s=
    [[ $desc == *'"uses_cache": true'* ]] && prep=${pre_s:-0}
    if [[ $desc == *'"learns": true'* ]] && train "$name" "$scene" "$dir" "$size" "$mode"; then
      field_of[$mode]=$dir/fields-$size/$mode.field
      train_s=$(cat "$dir/fields-$size/$mode.seconds")
      prep=$(awk -v a="$prep" -v b="${train_s:-0}" 'BEGIN{printf "%.2f", a + b}')
    fi
    prep_of[$mode]=$prep
    printf '| %s | %s | %s | %s | %s |\n' "$name" "$mode" \
      "$([[ $desc == *'"uses_cache": true'* ]] && echo "${pre_s:-?}" || echo -)" "${train_s:--}" "$prep" \
      >>"$tables/preparation.md"
  done
  runs=$dir/runs
  rm -rf "$runs"; mkdir -p "$runs"
  for seed in $(seq "$seeds"); do
    # modes interleaved, the order rotated per seed: load changes hit all alike
    for k in "${!modes[@]}"; do
      mode=${modes[$(((k + seed - 1) % ${#modes[@]}))]}
      note "$name: $mode, seed $seed/$seeds, $seconds s"
      field=()
      [ -n "${field_of[$mode]:-}" ] && field=(--field "${field_of[$mode]}")
      # shellcheck disable=SC2046
      "$bin/render" "$scene" --cache "$dir/importance.cache" $(options_of "$mode") "${field[@]}" \
        --time "$seconds" --seed "$seed" --size "$size" --reference "$refdir/ref.exr" \
        --log "$runs/$mode-$seed.csv" -o "$runs/$mode-$seed.exr" --quiet 2>"$runs/$mode-$seed.err" ||
        notes+=("$name: $mode seed $seed failed: $(tail -1 "$runs/$mode-$seed.err")")
    done
  done
  # the same runs with each mode's preparation on its clock
  prepared=$dir/runs-prepared
  rm -rf "$prepared"; mkdir -p "$prepared"
  for f in "$runs"/*.csv; do
    mode=$(basename "$f" .csv); mode=${mode%-*}
    awk -F, -v OFS=, -v p="${prep_of[$mode]:-0}" 'NR == 1 { print; next } { $1 = $1 + p; print }' "$f" \
      >"$prepared/$(basename "$f")"
    cp "${f%.csv}.exr" "$prepared/" 2>/dev/null
  done
  ref_args=()
  for k in relmse mse8 mse spp seconds state; do
    v=$(ref_field "$k" "$refdir/ref.txt")
    [ -n "$v" ] && ref_args+=("--ref-$k" "$v")
  done
  "$tool" analyze "$name" "$runs" "$seeds" "$tables" --modes "$mode_list" --size "$size" "${ref_args[@]}" \
    2>"$runs/analyze.err" ||
    { notes+=("$name: analyze failed: $(tail -1 "$runs/analyze.err")"); continue; }
  mkdir -p "$tables/prepared"
  "$tool" analyze "$name" "$prepared" "$seeds" "$tables/prepared" --modes "$mode_list" --size "$size" \
    "${ref_args[@]}" 2>"$prepared/analyze.err" ||
    notes+=("$name: analyze (preparation counted) failed: $(tail -1 "$prepared/analyze.err")")
  fig="![$name: relMSE and MSE against time]($report_link/$name-convergence.png)"
  if [ $have_gnuplot = 1 ]; then
    plot "$name" "$dir" "$size" "$runs/levels.txt" "$(ref_field relmse "$refdir/ref.txt")" \
      "$(ref_field mse "$refdir/ref.txt")" "$report_dir/$name-convergence.png"
  else
    fig="(no plot: gnuplot is not installed; make bench-deps installs it)"
  fi
  # seed 1 of every mode that has its image, then the reference
  strip=() shown=()
  for m in "${modes[@]}"; do
    [ -e "$runs/$m-1.exr" ] && { strip+=("$runs/$m-1.exr"); shown+=("$m"); }
  done
  crop=$("$tool" strip "$refdir/ref.exr" --exposure "$exposure" -o "$report_dir/$name-crops.png" \
           "${strip[@]}" 2>&1) ||
    notes+=("$name: crops failed: $crop")
  figures+=("**$name** ($size, exposure $exposure): relMSE (left) and linear MSE (right) against time; equal-time crops after $seconds s (seed 1), left to right $(printf '%s, ' "${shown[@]}")reference, ${crop#crop } (x,y,w,h: the square where bsdf's relative error is largest)"
            "$fig ![$name: equal-time crops]($report_link/$name-crops.png)")
done
note "done"; [ -t 2 ] && printf '\n' >&2

# table NAME: a table analyze wrote, its header first ("(no results)" when
# no scene got that far)
table() {
  local t=${2:-$tables}
  if [ -s "$t/$1.md" ]; then cat "$t/$1.head" "$t/$1.md"; else echo "(no results)"; fi
}
has_openpgl=0
[[ " ${modes[*]} " == *" openpgl "* ]] && has_openpgl=1
versus=
[ $has_openpgl = 1 ] && versus=" Guided over openpgl = openpgl seconds / guided seconds (> 1: guided gets there first)."

echo "Setting **$setting**: each scene's image scaled to about $pixels pixels (aspect kept); every run"
echo "$seconds s of rendering (\`render --time\`: scene loading, BVH and guide set-up excluded); $seeds seed(s) per"
echo "mode (${modes[*]}), modes interleaved within a seed; curves averaged over seeds on a common time grid (log-log"
echo "interpolation). References: \`render --sampling bsdf\`, two halves of the same spp (seeds 1001, 1002,"
echo "the first $ref_seconds s long) averaged; their own error is estimated from the halves' difference."
echo
echo "### References"
echo
table reference
echo
echo "An error measured against the reference is the run's own error plus the reference's (they are"
echo "independent): a curve cannot go below the reference's own error, drawn dashed in the plots."
echo
echo "### Preparation"
echo
echo "What each mode needs before its first sample, in seconds: the precompute (voxelize, skeletonize,"
echo "importance; wall time, scene loading included) for the modes that read the importance cache, and"
echo "the training of a mode that learns (\`render --field-out\`, at the runs' size, its passes as"
echo "render counts a run's time: scene loading and set-up excluded). Every run of a learned mode starts"
echo "from that stored field, frozen (\`render --field\`): nothing is learned on the run's clock."
echo
if [ -s "$tables/preparation.md" ]; then
  echo "| scene | mode | precompute s | training s | preparation s |"
  echo "|---|---|---|---|---|"
  cat "$tables/preparation.md"
else
  echo "(no results)"
fi
echo
echo "### Table 2: seconds to reach a relMSE level"
echo
echo "relMSE = mean over pixels and channels of (x - ref)^2 / (ref^2 + 0.01), on the linear image times"
echo "2^exposure (the scene's PNG exposure), so that dark scenes are measured relatively too."
echo "Levels per scene from bsdf alone, the same for every mode: bsdf's mean error at the end of its run"
echo "and at an eighth of it, rounded up to two digits. Speed-up = bsdf seconds / mode"
echo "seconds (> 1: faster than bsdf).$versus ~: extrapolated along 1/t from the last half of the curve;"
echo "< t: already below at the first pass; never: not reached and the curve too flat to extrapolate"
echo "(log-log slope above -0.5: a biased mode stuck on its bias)."
echo
table table2-relmse
echo
echo "### Table 2: seconds to reach an 8-bit MSE level (the paper's measure)"
echo
echo "mse8 = mean squared difference of the 8-bit sRGB values of the PNG at the scene's exposure (the"
echo "paper's MSE 100 and 40 were at its own exposures and image sizes). Same rules as above."
echo
table table2-mse8
echo
echo "### Table 2: seconds to reach a linear-radiance MSE level"
echo
echo "MSE = mean over pixels and channels of (x - ref)^2 on the linear radiance, no exposure and no"
echo "tone curve (\`render --log\`'s mse column): the brightest pixels weigh most, where relMSE and mse8"
echo "weigh every pixel more evenly, so a guide that spends its samples on dim regions can gain on those"
echo "two and lose on this one. Same rules as above."
echo
table table2-mse
echo
echo "### Table 2 with preparation counted: seconds to reach a relMSE level"
echo
echo "The same runs, each mode's curve moved right by its preparation (table above): the seconds from"
echo "nothing to the level, for a user who renders this scene once."
echo
table table2-relmse "$tables/prepared"
echo
echo "The same, for mse8 and for linear MSE:"
echo
table table2-mse8 "$tables/prepared"
echo
table table2-mse "$tables/prepared"
echo
echo "### Equal time"
echo
echo "Errors of the mean curves at the time every mode reached; ratio = bsdf error / mode error (for"
echo "unbiased modes, the speed-up); µs/sample: wall time per path over both cores."
echo
table equal-time
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
