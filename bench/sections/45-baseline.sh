#!/usr/bin/env bash
# Against an earlier build: render's per-sample cost on scenes without
# textures or microfacet materials (the corridor, the Cornell box), this
# commit's build against SG_BASELINE's (default 3079266, the last commit
# before textures and microfacet BSDFs came; built once from
# `git archive` into bench/out/baseline-REV, without Open PGL). The same
# seed and spp, so both trace the same paths (the images are compared too:
# identical means the same work); old and new alternate, best of each.
# Target: no slower per sample, within the noise of this
# machine: the last row, this build against itself the same way, shows
# that noise (ok within +3 %).
set -uo pipefail
bin=${SG_BIN:-bin}
rev=${SG_BASELINE:-3079266}
rounds=5
[ "${SG_QUICK:-0}" = 1 ] && rounds=2
field() { awk -v k="$1" '{for(i=1;i<NF;i++) if($(i+1)==k",") print $i}' <<<"$2"; }

for p in voxelize skeletonize importance render; do
  [ -x "$bin/$p" ] || { echo "(needs $bin/$p: run make)"; exit 0; }
done
if ! full=$(git rev-parse --verify --quiet "$rev^{commit}" 2>/dev/null); then
  echo "(baseline $rev is not in this clone's history: nothing to compare with)"
  exit 0
fi
base=bench/out/baseline-${full:0:12}
if [ ! -x "$base/bin/render" ]; then
  [ -t 2 ] && printf 'baseline: building render at %s\n' "$rev" >&2
  rm -rf "$base"; mkdir -p "$base"
  if ! { git archive "$full" | tar -x -C "$base" && make -C "$base" -j"$(nproc)" bin/render >"$base.log" 2>&1; }; then
    echo "(baseline $rev did not build: see $base.log)"
    exit 0
  fi
fi
source bench/precompute_steps.sh
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT

echo "| scene | sampling | spp | µs/sample at $rev | µs/sample now | now / then | same image | target |"
echo "|---|---|---|---|---|---|---|---|"
for sc in data/corridor/corridor.json data/cornell-box/cornell-box.json; do
  name=$(basename "$sc" .json)
  if ! precompute_steps "$bin" "$sc" "$out/$name"; then
    echo "| $name | precompute failed | | | | | | |"; continue
  fi
  runs=("bsdf $base/bin/render" "guided $base/bin/render")
  [ "$name" = corridor ] && runs+=("guided $bin/render")
  for run in "${runs[@]}"; do
    read -r mode then <<<"$run"
    best_old=999 best_new=999
    for _ in $(seq "$rounds"); do
      for who in old new; do
        r=$bin/render; [ $who = old ] && r=$then
        # this build without its edge rays (docs/render.md, "Edge rays"):
        # the baseline has none, and the same work is what is compared
        no_edges=(); [ "$r" = "$bin/render" ] && no_edges=(--edge-rays 0)
        line=$("$r" "$sc" --cache "$out/$name/importance.cache" --sampling $mode --spp 64 --seed 7 \
                 "${no_edges[@]}" -o "$out/$who.exr" 2>&1) || { echo "| $name | $mode: $who failed: ${line##*$'\n'} | | | | | | |"; continue 3; }
        us=$(awk -v x="$(field Msamples/s "$line")" 'BEGIN{print 1/x}')
        if [ $who = old ]; then best_old=$(awk -v a=$best_old -v b="$us" 'BEGIN{print (b<a)?b:a}')
        else best_new=$(awk -v a=$best_new -v b="$us" 'BEGIN{print (b<a)?b:a}'); fi
      done
    done
    same=no
    idiff -fail 0 -warn 0 "$out/old.exr" "$out/new.exr" >/dev/null 2>&1 && same=yes
    label=$mode; [ "$then" = "$bin/render" ] && label="$mode (control: this build against itself)"
    awk -v n="$name" -v m="$label" -v o="$best_old" -v c="$best_new" -v s=$same 'BEGIN{
      r = c / o
      printf "| %s | %s | 64 | %.4f | %.4f | %.3f | %s | %s |\n", n, m, o, c, r, s,
             (r <= 1.03) ? "no slower: ok" : "SLOWER"}'
  done
done
echo
echo "(all cores, best of $rounds alternated runs each; the baseline is bench/out/baseline-${full:0:12}/bin/render)"
