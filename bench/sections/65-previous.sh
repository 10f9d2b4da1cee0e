#!/usr/bin/env bash
# Against the previous build, at equal time: every scene of the convergence
# race, every column, rendered for the same seconds by this build and by the
# one the committed report measured (SG_PREVIOUS, default the commit in
# bench/report.md's header; built once from `git archive` into
# bench/out/previous-REV, with Open PGL where this build has it), each build
# on its own precompute (the cache's format may have changed), both against
# the convergence section's reference, each mode learning on the clock as a user's
# `render --time` does. A change that makes any mode's error worse shows
# here, on every scene, whatever it did to speed. Settings follow section
# 60's (SG_QUICK, SG_LONG); SG_PREVIOUS_SECONDS, SG_PREVIOUS_SEEDS and
# SG_CONV_SCENES override.
set -uo pipefail
bin=${SG_BIN:-bin}
tool=${SG_BENCH_BIN:-build/release/bench}/convergence
source bench/scenes.sh
source bench/precompute_steps.sh

seconds=${SG_PREVIOUS_SECONDS:-$(by_setting 3 60 6)}
seeds=${SG_PREVIOUS_SEEDS:-$(by_setting 1 2 2)}
# worse beyond this ratio of errors (the runs' own noise is some 10 %)
WORSE=1.2

note() { [ -t 2 ] && printf '\r\033[Kprevious: %s' "$*" >&2; return 0; }
bench_needs voxelize skeletonize importance render

rev=${SG_PREVIOUS:-$(sed -nE 's/^\| code \| commit ([0-9a-f]+).*/\1/p' bench/report.md 2>/dev/null | head -1)}
if [ -z "$rev" ] || ! full=$(git rev-parse --verify --quiet "$rev^{commit}" 2>/dev/null); then
  echo "(no previous build to compare with: bench/report.md names no commit of this clone's history${rev:+ ($rev)})"
  exit 0
fi
if [ "$full" = "$(git rev-parse HEAD)" ] && [ -z "$(git status --porcelain --untracked-files=no)" ]; then
  echo "(the previous report measured this very commit, ${full:0:12}: nothing to compare)"
  exit 0
fi
prev=bench/out/previous-${full:0:12}
pgl=()
[ -e build/openpgl/install/include/openpgl/openpgl.h ] && pgl=(OPENPGL_DIR="$PWD/build/openpgl/install")
[ -n "${OPENPGL_DIR:-}" ] && pgl=(OPENPGL_DIR="$OPENPGL_DIR")
if [ ! -x "$prev/bin/render" ]; then
  note "building ${full:0:12}"
  rm -rf "$prev"; mkdir -p "$prev"
  if ! { git archive "$full" | tar -x -C "$prev" &&
         make -C "$prev" -j"$(nproc)" "${pgl[@]}" all >"$prev.log" 2>&1; }; then
    echo "(the previous build, ${full:0:12}, did not build: see $prev.log)"
    exit 0
  fi
fi

runs=$(mktemp -d)
trap 'rm -rf "$runs"' EXIT
notes=() rows=()
# final ERR: the last row's relMSE and linear MSE of a run's log
final() { tail -1 "$1" | awk -F, '{print $4, $3}'; }

for entry in "${bench_scenes[@]}"; do
  IFS='|' read -r name scene resolution <<<"$entry"
  if [ -n "${SG_CONV_SCENES:-}" ] && [[ " $SG_CONV_SCENES " != *" $name "* ]]; then continue; fi
  ref=bench/out/$name/ref-$setting/ref.exr now_cache=bench/out/$name/importance.cache
  if [ ! -e "$ref" ] || [ ! -e "$now_cache" ]; then
    notes+=("$name: no reference or cache from the convergence section: skipped"); continue
  fi
  read -r size _ < <("$tool" size "$scene" "$pixels") || { notes+=("$name: cannot read the scene"); continue; }
  # the previous build's precompute, once per scene and build
  pdir=$prev/out/$name
  if [ ! -e "$pdir/importance.cache" ]; then
    note "$name: the previous build's precompute"
    if ! precompute_steps "$prev/bin" "$scene" "$pdir" "$resolution"; then
      notes+=("$name: the previous build cannot precompute it: $(tail -1 "$pdir/precompute.log")")
      rm -f "$pdir/importance.cache"; continue
    fi
  fi
  for mode in "${bench_modes[@]}"; do
    declare -A sum=([then-rel]=0 [then-mse]=0 [now-rel]=0 [now-mse]=0)
    failed=
    for seed in $(seq "$seeds"); do
      for who in then now; do # alternated: load changes hit both alike
        r=$bin/render cache=$now_cache
        [ $who = then ] && r=$prev/bin/render cache=$pdir/importance.cache
        note "$name: $mode, seed $seed/$seeds, $who, $seconds s"
        # shellcheck disable=SC2046
        if ! "$r" "$scene" --cache "$cache" $(options_of "$mode") --time "$seconds" --seed "$seed" \
               --size "$size" --reference "$ref" --log "$runs/$who.csv" -o "$runs/$who.exr" --quiet \
               2>"$runs/$who.err"; then
          failed="$who: $(tail -1 "$runs/$who.err")"; break 2
        fi
        read -r rel mse < <(final "$runs/$who.csv")
        sum[$who-rel]=$(awk -v a="${sum[$who-rel]}" -v b="$rel" 'BEGIN{print a + b}')
        sum[$who-mse]=$(awk -v a="${sum[$who-mse]}" -v b="$mse" 'BEGIN{print a + b}')
      done
    done
    if [ -n "$failed" ]; then
      rows+=("| $name | $mode | | | | | | | not compared ($failed) |"); continue
    fi
    rows+=("$(awk -v n="$name" -v m="$mode" -v k="$seeds" -v w=$WORSE -v tr="${sum[then-rel]}" \
                -v nr="${sum[now-rel]}" -v tm="${sum[then-mse]}" -v nm="${sum[now-mse]}" 'BEGIN{
      rr = (tr > 0) ? nr / tr : 1; rm = (tm > 0) ? nm / tm : 1
      v = (rr > w || rm > w) ? "WORSE" : (rr < 1 / w && rm < 1 / w) ? "better" : "ok"
      printf "| %s | %s | %.3g | %.3g | %.2f | %.3g | %.3g | %.2f | %s |", n, m, tr / k, nr / k, rr,
             tm / k, nm / k, rm, v }')")
  done
done
note "done"; [ -t 2 ] && printf '\n' >&2

worse=0
for row in "${rows[@]}"; do [[ $row == *"| WORSE |" ]] && worse=$((worse + 1)); done
echo "Every column of the convergence race on every scene, $seconds s of rendering each (\`render --time\`,"
echo "learning on the clock), $seeds seed(s), this build (now) against the previous one (then:"
echo "${full:0:12}, ${SG_PREVIOUS:+SG_PREVIOUS}${SG_PREVIOUS:-the commit the committed report measured}; \`$prev\`), each on its own"
echo "precompute, against the convergence section's reference; errors are the runs' means at the end of their time."
echo "ratio = now / then (< 1: now is better). WORSE: relMSE or linear MSE more than ${WORSE}x then's;"
echo "better: both below 1/${WORSE}."
echo
echo "| scene | mode | relMSE then | relMSE now | ratio | MSE then | MSE now | ratio | verdict |"
echo "|---|---|---|---|---|---|---|---|---|"
print_rows
echo
if [ $worse -gt 0 ]; then
  echo "**$worse row(s) WORSE than the previous build.**"
else
  echo "No row worse than the previous build."
fi
print_notes
exit 0
