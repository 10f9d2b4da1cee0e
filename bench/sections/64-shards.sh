#!/usr/bin/env bash
# The render farm: a learned mode rendered in 16 shards from one stored
# field (`render --field F --shard K/16`, then `bin/merge`), as
# scripts/slurm-render.sh renders it, against one process with the same
# field, the same seed and the same samples in all. Each learned mode's
# field and the reference are the convergence section's; bsdf, which learns nothing,
# beside them. The shards differ from one process only where a shard
# estimates something from its own passes: guided's learned roulette (each
# pixel's noise) and, in every mode, how many edge rays a silhouette in
# view takes. Target: relMSE within 10% of one process.
# Scenes: SG_SHARD_SCENES (default: the corridor, no light in view, and the
# Cornell box, its light in view); settings follow the convergence section's.
set -uo pipefail
bin=${SG_BIN:-bin}
tool=${SG_BENCH_BIN:-build/release/bench}/convergence
source bench/scenes.sh

spp=$(by_setting 32 256 128) seeds=$(by_setting 1 2 2)
shards=16
# more than this ratio of one process's relMSE misses the target
WITHIN=1.10
# the baseline, which learns nothing, and every column whose mode learns
modes=("$bench_baseline")
for column in "${bench_modes[@]}"; do mode_says "$(mode_of "$column")" learns && modes+=("$column"); done

note() { [ -t 2 ] && printf '\r\033[Kshards: %s' "$*" >&2; return 0; }
bench_needs render merge

runs=$(mktemp -d)
trap 'rm -rf "$runs"' EXIT
rows=() notes=() missed=0
for entry in "${bench_scenes[@]}"; do
  IFS='|' read -r name scene _ <<<"$entry"
  [[ " ${SG_SHARD_SCENES:-corridor cornell-box} " == *" $name "* ]] || continue
  dir=bench/out/$name ref=bench/out/$name/ref-$setting/ref.exr
  read -r size exposure < <("$tool" size "$scene" "$pixels") || { notes+=("$name: cannot read the scene"); continue; }
  if [ ! -e "$ref" ] || [ ! -e "$dir/importance.cache" ]; then
    notes+=("$name: no reference or cache from the convergence section: skipped"); continue
  fi
  for mode in "${modes[@]}"; do
    field=()
    if mode_says "$(mode_of "$mode")" learns; then
      [ -e "$dir/fields-$size/$mode.field" ] || { notes+=("$name: no $mode field from the convergence section: skipped"); continue; }
      field=(--field "$dir/fields-$size/$mode.field")
    fi
    for seed in $(seq "$seeds"); do
      common=("$scene" --cache "$dir/importance.cache" "${field[@]}" --size "$size" --spp "$spp"
              --seed "$seed" --quiet)
      note "$name: $mode, seed $seed, one process"
      # shellcheck disable=SC2046
      if ! "$bin/render" "${common[@]}" $(options_of "$mode") -o "$runs/one.exr" 2>"$runs/err"; then
        rows+=("| $name | $mode | $seed | | | | | | not measured ($(tail -1 "$runs/err")) |"); continue
      fi
      rm -f "$runs"/shard-*.exr
      failed=
      for k in $(seq 0 $((shards - 1))); do
        note "$name: $mode, seed $seed, shard $((k + 1))/$shards"
        # shellcheck disable=SC2046
        "$bin/render" "${common[@]}" $(options_of "$mode") --shard "$k/$shards" \
          -o "$runs/shard-$k.exr" 2>"$runs/err" || { failed=$(tail -1 "$runs/err"); break; }
      done
      [ -z "$failed" ] && { "$bin/merge" "$runs"/shard-*.exr -o "$runs/merged.exr" --quiet 2>"$runs/err" ||
                            failed=$(tail -1 "$runs/err"); }
      if [ -n "$failed" ]; then
        rows+=("| $name | $mode | $seed | | | | | | not measured ($failed) |"); continue
      fi
      one=$("$tool" error "$runs/one.exr" "$ref" --exposure "$exposure")
      merged=$("$tool" error "$runs/merged.exr" "$ref" --exposure "$exposure")
      row=$(awk -v n="$name" -v m="$mode" -v s="$seed" -v w=$WITHIN -v a="$one" -v b="$merged" 'BEGIN{
        split(a, x, " "); split(b, y, " ")   # relmse R mse8 E mse M
        r = y[2] / x[2]; e = y[4] / x[4]; q = y[6] / x[6]
        printf "| %s | %s | %s | %.4g | %.4g | %+.2f%% | %+.2f%% | %+.2f%% | %s |", n, m, s, x[2], y[2],
               100 * (r - 1), 100 * (e - 1), 100 * (q - 1), (r <= w) ? "ok" : "MISSED" }')
      [[ $row == *"| MISSED |" ]] && missed=$((missed + 1))
      rows+=("$row")
    done
  done
done
note "done"; [ -t 2 ] && printf '\n' >&2

echo "Each learned mode from the convergence section's stored field (bsdf learns nothing), $spp spp in all, at section"
echo "60's size: one \`render --field F --spp $spp\` against $shards \`render --field F --spp $spp --shard K/$shards\` merged by"
echo "\`bin/merge\`; the same seed, so both render the same passes; errors against the convergence section's reference"
echo "(\`convergence error\`). Change: merged over one process, less 1. Target: relMSE within"
echo "$(awk -v w=$WITHIN 'BEGIN{printf "%d", 100 * (w - 1) + 0.5}')% of one process."
echo
echo "| scene | mode | seed | relMSE one process | relMSE $shards shards | relMSE change | mse8 change | MSE change | target |"
echo "|---|---|---|---|---|---|---|---|---|"
print_rows
echo
if [ ${#rows[@]} -eq 0 ]; then
  echo "Nothing measured."
elif [ $missed -gt 0 ]; then
  echo "**$missed row(s) MISSED the target.**"
else
  echo "Every row within the target."
fi
print_notes
exit 0
