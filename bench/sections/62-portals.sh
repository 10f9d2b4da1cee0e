#!/usr/bin/env bash
# Portals found by the skeleton's precompute: on every scene of
# the convergence race lit by a sky, guided at equal time with the sky's
# light samples through the openings render finds (its default) and over
# the sky's whole sphere (--no-openings, the sky's own importance sampling),
# each from a field trained alone with the same option, against the
# convergence section's reference. Target: >= 2x in relMSE on a window-lit scene, no slower
# anywhere else. Settings follow the convergence section's (SG_QUICK, SG_LONG);
# SG_PORTAL_SECONDS, SG_PORTAL_SEEDS and SG_CONV_SCENES override.
set -uo pipefail
bin=${SG_BIN:-bin}
tool=${SG_BENCH_BIN:-build/release/bench}/convergence
source bench/scenes.sh

seconds=${SG_PORTAL_SECONDS:-$(by_setting 3 60 10)}
seeds=${SG_PORTAL_SEEDS:-$(by_setting 1 3 3)}

note() { [ -t 2 ] && printf '\r\033[Kportals: %s' "$*" >&2; return 0; }
bench_needs render

runs=$(mktemp -d)
trap 'rm -rf "$runs"' EXIT
notes=() rows=()
final() { tail -1 "$1" | awk -F, '{print $4, $3, $5}'; }
mean() { awk '{ s += $1; n++ } END { if (n) printf "%.4g", s / n }'; }

for entry in "${bench_scenes[@]}"; do
  IFS='|' read -r name scene _ <<<"$entry"
  if [ -n "${SG_CONV_SCENES:-}" ] && [[ " $SG_CONV_SCENES " != *" $name "* ]]; then continue; fi
  dir=bench/out/$name
  ref=$dir/ref-$setting/ref.exr cache=$dir/importance.cache
  [ -e "$ref" ] && [ -e "$cache" ] || { notes+=("$name: no reference or cache from the convergence section: skipped"); continue; }
  read -r size _ < <("$tool" size "$scene" "$pixels") || { notes+=("$name: cannot read the scene"); continue; }
  # a scene with a sky: guided reports the openings it samples it through
  probe=$("$bin/render" "$scene" --cache "$cache" --sampling guided --alpha 0.5 --spp 1 --size 8x6 \
            -o "$runs/probe.exr" 2>&1) || { notes+=("$name: ${probe##*$'\n'}"); continue; }
  openings=$(sed -nE 's/.*sky sampled through ([0-9]+) opening.*/\1/p' <<<"$probe")
  [ -n "$openings" ] || continue
  fdir=$dir/fields-$size
  mkdir -p "$fdir"
  declare -A fields=([through]=$fdir/guided.field [sphere]=$fdir/guided-no-openings.field)
  declare -A extra=([through]="" [sphere]="--no-openings")
  failed=
  for way in through sphere; do
    f=${fields[$way]}
    if [ -e "$f" ] && [ "$f" -nt "$bin/render" ] && [ "$f" -nt "$cache" ]; then continue; fi
    note "$name: training, $way"
    # shellcheck disable=SC2086
    line=$("$bin/render" "$scene" --cache "$cache" --sampling guided ${extra[$way]} --seed 999 --size "$size" \
             --field-out "$f" -o "$runs/training.exr" 2>&1) || { failed="training: ${line##*$'\n'}"; break; }
  done
  [ -z "$failed" ] || { notes+=("$name: $failed"); continue; }
  : >"$runs/through" ; : >"$runs/sphere"
  for seed in $(seq "$seeds"); do
    for way in through sphere; do # alternated: load changes hit both alike
      note "$name: seed $seed/$seeds, $way, $seconds s"
      # shellcheck disable=SC2086
      if ! "$bin/render" "$scene" --cache "$cache" --sampling guided ${extra[$way]} --field "${fields[$way]}" \
             --time "$seconds" --seed "$seed" --size "$size" --reference "$ref" --log "$runs/run.csv" \
             -o "$runs/run.exr" --quiet 2>"$runs/run.err"; then
        failed="$way seed $seed: $(tail -1 "$runs/run.err")"; break 2
      fi
      final "$runs/run.csv" >>"$runs/$way"
    done
  done
  [ -z "$failed" ] || { notes+=("$name: $failed"); continue; }
  rel_t=$(cut -d' ' -f1 "$runs/through" | mean) rel_s=$(cut -d' ' -f1 "$runs/sphere" | mean)
  mse_t=$(cut -d' ' -f2 "$runs/through" | mean) mse_s=$(cut -d' ' -f2 "$runs/sphere" | mean)
  m8_t=$(cut -d' ' -f3 "$runs/through" | mean) m8_s=$(cut -d' ' -f3 "$runs/sphere" | mean)
  # the reference's own error (the convergence section measures it from its two halves)
  # is in both modes' errors: each less it is the error against the truth
  # (independent noise adds); a reference as noisy as the modes pulls the
  # raw gain toward 1
  own=$(ref_field relmse "$dir/ref-$setting/ref.txt" 2>/dev/null)
  rows+=("$(awk -v n="$name" -v o="$openings" -v a="$rel_s" -v b="$rel_t" -v c="$mse_s" -v d="$mse_t" \
              -v e="$m8_s" -v f="$m8_t" -v r="${own:-}" 'BEGIN{
    net = "-"
    if (r != "" && b - r > 0 && a - r > 0) net = sprintf("%.2fx (%.3g / %.3g)", (a - r) / (b - r), a - r, b - r)
    else if (r != "") net = sprintf("- (the reference own %.3g)", r)
    printf "| %s | %d | %.3g | %.3g | %.2fx | %s | %.3g | %.3g | %.2fx | %.4g | %.4g | %.2fx |", n, o, a, b,
           (b > 0) ? a / b : 0, net, c, d, (d > 0) ? c / d : 0, e, f, (f > 0) ? e / f : 0 }')")
done
note "done"; [ -t 2 ] && printf '\n' >&2

echo "The sky's light samples through the openings the precompute found (render's default with a"
echo "cache) against over its whole sphere (\`--no-openings\`: the sky image's own importance sampling),"
echo "\`guided\` from a field trained with the same choice, $seconds s of rendering each, $seeds seed(s),"
echo "the two alternated; errors are the means at the end of the runs against the convergence section's reference;"
echo "gain = sphere / openings (> 1: the openings help). Scenes with no sky have no openings and are"
echo "left out (their light sampling is the same either way). Target: gain >= 2x in relMSE on a"
echo "window-lit scene whose camera sees the sky's light first hand, judged on the gain"
echo "less the reference's own relMSE (the convergence section's estimate from its two halves, taken from both"
echo "errors: independent noise adds; \"-\" where a mode is not above it)."
echo
echo "| scene | openings | relMSE sphere | relMSE openings | gain | gain less the reference's own error | MSE sphere | MSE openings | gain | mse8 sphere | mse8 openings | gain |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
[ ${#rows[@]} -gt 0 ] || echo "| (no scene with a sky) | | | | | | | | | | | |"
print_rows
print_notes
exit 0
