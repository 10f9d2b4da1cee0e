#!/usr/bin/env bash
# Every second counted, from the scene file to the image: for bsdf, guided
# and openpgl, each run as a user runs it (guided: the precompute, then one
# render that learns within itself and keeps every pass; openpgl: trained
# inside its render as Cycles does, its samples kept; bsdf: the render),
# the wall time to reach bsdf's final error, and the error at fixed budgets
# of 3, 10, 30 and 100 s (a mode that learns, from a run of that budget
# of its own: it plans its learning by the budget). Errors: relMSE with the worst 0.1 % of the
# pixels' errors left out (trimmed), and linear MSE, each the mean over the
# seeds with its spread; plain relMSE beside. The references are the
# convergence race's (run it first); the bench's scenes, or SG_E2E_SCENES,
# and scenes the bench never saw in SG_E2E_EXTRA ("name|scene|resolution"
# entries, their references in SG_E2E_REF_ROOT/name/ref.exr).
set -uo pipefail
bin=${SG_BIN:-bin}
tool=${SG_BENCH_BIN:-build/release/bench}/convergence
source bench/scenes.sh

if [ "${SG_QUICK:-0}" = 1 ]; then
  setting=quick pixels=9600 budget=10 seeds=2
elif [ "${SG_LONG:-0}" = 1 ]; then
  setting=long pixels=921600 budget=100 seeds=5
else
  setting=default pixels=76800 budget=30 seeds=3 # 100 s runs would add two hours to make bench
fi
pixels=${SG_E2E_PIXELS:-$pixels} budget=${SG_E2E_SECONDS:-$budget} seeds=${SG_E2E_SEEDS:-$seeds}
budgets=(3 10 30 100)
modes=(bsdf guided openpgl)
# shellcheck disable=SC2206
[ -n "${SG_E2E_EXTRA:-}" ] && bench_scenes+=($SG_E2E_EXTRA)

note() { [ -t 2 ] && printf '\r\033[Ke2e: %s' "$*" >&2; return 0; }
for p in voxelize skeletonize importance render; do
  [ -x "$bin/$p" ] || { echo "(needs $bin/$p: run make)"; exit 0; }
done
[ -x "$tool" ] || { echo "(needs $tool: run make bench)"; exit 0; }
"$bin/render" --describe openpgl | grep -q '"available": true' || modes=(bsdf guided)
# shellcheck disable=SC2207
learning_modes=($("$bin/render" --describe | sed -n 's/.*"name": "\([a-z]*\)".*"learns": true.*/\1/p'))

now() { date +%s.%N; }
# e2e_rows CSV PREP OVERHEAD: the log's rows with the wall time since the
# scene file in front: seconds spp mse relmse mse8 relmse_trimmed
e2e_rows() { awk -F, -v p="$2" -v o="$3" 'NR > 1 { print p + o + $1, $2, $3, $4, $5, $6 }' "$1"; }
# at_budget ROWS B COLUMN: the column at the last row within B seconds ("-": none)
at_budget() { awk -v b="$2" -v c="$3" '$1 <= b { v = $c } END { print (v == "" ? "-" : v) }' "$1"; }
# time_to ROWS LEVEL COLUMN: the time from which the column stays at or
# below LEVEL ("-": never; a relative error can dip early, when the first
# passes see nothing where the image is dark)
time_to() { awk -v l="$2" -v c="$3" '$c > l { t = "" } $c <= l && t == "" { t = $1 } END { print (t == "" ? "-" : t) }' "$1"; }
# mean_spread VALUES...: "mean ± spread" (spread: half the range), "-" if any is missing
mean_spread() {
  printf '%s\n' "$@" | awk '$1 == "-" { miss = 1 } { n++; s += $1; if (n == 1 || $1 < lo) lo = $1; if (n == 1 || $1 > hi) hi = $1 }
    END { if (miss || !n) print "-"; else printf "%.3g ± %.2g\n", s / n, (hi - lo) / 2 }'
}
mean_of() { printf '%s\n' "$@" | awk '$1 == "-" { miss = 1 } { n++; s += $1 } END { if (miss || !n) print "-"; else printf "%.3g\n", s / n }'; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
notes=() speed_rows=() budget_rows=()
for entry in "${bench_scenes[@]}"; do
  IFS='|' read -r name scene resolution <<<"$entry"
  [ -z "${SG_E2E_SCENES:-}" ] || [[ " $SG_E2E_SCENES " == *" $name "* ]] || continue
  [ -e "$scene" ] || { notes+=("$name: $scene is absent: skipped"); continue; }
  ref=bench/out/$name/ref-$setting/ref.exr
  [ -n "${SG_E2E_REF_ROOT:-}" ] && ref=$SG_E2E_REF_ROOT/$name/ref.exr
  [ -e "$ref" ] || { notes+=("$name: no reference ($ref: the convergence race makes it): skipped"); continue; }
  read -r size exposure < <("$tool" size "$scene" "$pixels") || { notes+=("$name: cannot read the scene"); continue; }
  dir=$work/$name
  mkdir -p "$dir"
  # the precompute, timed as a user pays it
  note "$name: precompute"
  t0=$(now)
  res=(); [ -n "$resolution" ] && res=(--resolution "$resolution")
  if ! { "$bin/voxelize" "$scene" -o "$dir/medium.vdb" "${res[@]}" --quiet &&
         "$bin/skeletonize" "$dir/medium.vdb" -o "$dir/skeleton.ply" --quiet &&
         "$bin/importance" "$dir/medium.vdb" "$dir/skeleton.ply" -o "$dir/importance.cache" --quiet; } 2>"$dir/err"; then
    notes+=("$name: precompute failed: $(tail -1 "$dir/err")"); continue
  fi
  prep=$(awk -v a="$t0" -v b="$(now)" 'BEGIN { print b - a }')
  for mode in "${modes[@]}"; do
    for seed in $(seq "$seeds"); do
      note "$name: $mode, seed $seed"
      cache=() p=0
      if [ "$mode" = guided ]; then cache=(--cache "$dir/importance.cache"); p=$prep; fi
      if ! "$bin/render" "$scene" "${cache[@]}" --sampling "$mode" --size "$size" --time "$budget" --seed "$seed" \
          --reference "$ref" --log "$dir/$mode-$seed.csv" -o "$dir/$mode-$seed.exr" --quiet 2>"$dir/err"; then
        notes+=("$name: $mode seed $seed failed: $(tail -1 "$dir/err")"); continue
      fi
      # the render's own set-up (the scene read, the cache opened, the
      # renderer made) comes before its first pass; measuring the error
      # after each pass is not counted
      setup=$(oiiotool --info -v "$dir/$mode-$seed.exr" 2>/dev/null | sed -n 's/.*sg:setup_seconds: "\(.*\)"/\1/p')
      e2e_rows "$dir/$mode-$seed.csv" "$p" "${setup:-0}" >"$dir/$mode-$seed.rows"
      # a mode that learns plans its learning by its budget: a user with
      # fewer seconds runs it with those, and gets what the run's earlier
      # passes would not show (it learned for a longer run)
      [[ " ${learning_modes[*]} " == *" $mode "* ]] || continue
      for b in "${budgets[@]}"; do
        t=$(awk -v b="$b" -v t="$budget" -v p="$p" -v s="${setup:-0}" 'BEGIN { if (b < t - 0.5 && b - p - s > 0) print b - p - s }')
        [ -n "$t" ] || continue
        "$bin/render" "$scene" "${cache[@]}" --sampling "$mode" --size "$size" --time "$t" --seed "$seed" \
          --reference "$ref" --log "$dir/$mode-$seed-b$b.csv" -o "$dir/$mode-$seed-b$b.exr" --quiet 2>"$dir/err" &&
          e2e_rows "$dir/$mode-$seed-b$b.csv" "$p" "${setup:-0}" >"$dir/$mode-$seed-b$b.rows"
      done
    done
  done
  # bsdf's final level, per measure: the highest of its seeds' final errors (each of its runs reaches it)
  max_of() { printf '%s\n' "$@" | awk '$1 == "-" || $1 == "" { miss = 1 } $1 > m { m = $1 } END { print (miss ? "-" : m) }'; }
  level_t=$(max_of $(for s in $(seq "$seeds"); do tail -1 "$dir/bsdf-$s.rows" 2>/dev/null | cut -d' ' -f6 || echo -; done))
  level_m=$(max_of $(for s in $(seq "$seeds"); do tail -1 "$dir/bsdf-$s.rows" 2>/dev/null | cut -d' ' -f3 || echo -; done))
  declare -A reach_t reach_m
  for mode in "${modes[@]}"; do
    reach_t[$mode]=$(mean_of $(for s in $(seq "$seeds"); do time_to "$dir/$mode-$s.rows" "$level_t" 6; done))
    reach_m[$mode]=$(mean_of $(for s in $(seq "$seeds"); do time_to "$dir/$mode-$s.rows" "$level_m" 3; done))
  done
  ratio() { awk -v a="$1" -v b="$2" 'BEGIN { if (a == "-" || b == "-" || b <= 0) print "-"; else printf "%.2fx\n", a / b }'; }
  row="| $name | $size | $(printf '%.2f' "$prep") s |"
  for mode in "${modes[@]}"; do row+=" ${reach_t[$mode]} / ${reach_m[$mode]} |"; done
  row+=" $(ratio "${reach_t[bsdf]}" "${reach_t[guided]}") / $(ratio "${reach_m[bsdf]}" "${reach_m[guided]}") |"
  [ -n "${reach_t[openpgl]:-}" ] &&
    row+=" $(ratio "${reach_t[openpgl]}" "${reach_t[guided]}") / $(ratio "${reach_m[openpgl]}" "${reach_m[guided]}") |"
  speed_rows+=("$row")
  for b in "${budgets[@]}"; do
    (( $(awk -v b="$b" -v t="$budget" 'BEGIN { print (b <= t + 0.5) }') )) || continue
    row="| $name | $b s |"
    for mode in "${modes[@]}"; do
      vt=() vm=() vr=()
      for s in $(seq "$seeds"); do
        rows=$dir/$mode-$s.rows
        [ -e "$dir/$mode-$s-b$b.rows" ] && rows=$dir/$mode-$s-b$b.rows
        vt+=("$(at_budget "$rows" "$b" 6)"); vm+=("$(at_budget "$rows" "$b" 3)"); vr+=("$(at_budget "$rows" "$b" 4)")
      done
      row+=" $(mean_spread "${vt[@]}") | $(mean_spread "${vm[@]}") | $(mean_spread "${vr[@]}") |"
    done
    budget_rows+=("$row")
  done
  unset reach_t reach_m
done
[ -t 2 ] && printf '\r\033[K' >&2

echo "Setting: $setting ($pixels pixels, runs of $budget s, $seeds seeds; \`$bin/render --time\` from the"
echo "scene file, guided's precompute counted, every learned pass kept)."
echo
echo "**Seconds from the scene file to bsdf's final error** (mean over the seeds; trimmed relMSE /"
echo "linear MSE; - : not reached within the run), and guided's speed-up over bsdf and openpgl:"
echo
head="| scene | size | guided's precompute |"
sep="|---|---|---|"
for mode in "${modes[@]}"; do head+=" $mode |"; sep+="---|"; done
head+=" guided over bsdf |"; sep+="---|"
[ "${#modes[@]}" -gt 2 ] && { head+=" guided over openpgl |"; sep+="---|"; }
echo "$head"; echo "$sep"
printf '%s\n' "${speed_rows[@]}"
echo
echo "**Error at fixed budgets**, everything counted (mean ± half the range over the seeds; a mode that"
echo "learns, from runs of that budget: it plans its learning by it):"
echo
head="| scene | budget |" sep="|---|---|"
for mode in "${modes[@]}"; do head+=" $mode trimmed relMSE | $mode MSE | $mode relMSE |"; sep+="---|---|---|"; done
echo "$head"; echo "$sep"
printf '%s\n' "${budget_rows[@]}"
for n in "${notes[@]}"; do echo; echo "- $n"; done
exit 0
