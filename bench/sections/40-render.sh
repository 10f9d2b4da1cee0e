#!/usr/bin/env bash
# Render speed and the gain of guiding (issue 5):
#  1. samples/s of bin/render (bsdf) on Dabrovic Sponza, 320x240, path length 8,
#     against Embree's tutorial path tracer (embree-tools `pathtracer --benchmark`),
#     same camera, a light at the same place; run alternately, best of each.
#  2. per-sample cost of guided over bsdf (needs the precompute: voxelize,
#     skeletonize, importance).
#  3. time to reach a given error, guided vs bsdf, on the dark corridor and the
#     Cornell box, against a long reference render; curves averaged over seeds.
set -uo pipefail
bin=${SG_BIN:-bin}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
quick=${SG_QUICK:-0}
runs=3; [ "$quick" = 1 ] && runs=1

sponza=data/sponza/sponza-bench.json
# the light of sponza-bench.json, as a point light for pathtracer (it ignores Ke):
# a 0.2 m square of radiance 1250 facing down ~ intensity 50 straight down
pt_light=(--pointlight -13.5 5.89 -5 50 50 50)
pt_camera=(--vp 2.25067 8.24132 -0.0492483 --vi 3.15037 7.8048 -0.0501832
           --vu 0.436514 0.899693 -0.00291584 --fov 80.2 --size 320 240)
sponza_obj=../shared/scenes/sponza-dabrovic/sponza.obj

field() { sed -nE "s|.* ([0-9.]+) $1.*|\1|p" <<<"$2" | tail -1; }

echo "-- throughput: Sponza 320x240, path length 8, 1 spp passes, all cores"
if [ ! -e "$sponza_obj" ]; then
  echo "(Sponza not present: $sponza_obj)"
elif ! command -v pathtracer >/dev/null; then
  echo "(pathtracer from embree-tools not installed)"
else
  best_pt=0 best_pt_rays=0 best_sg=0 best_sg_rays=0
  frames=10; [ "$quick" = 1 ] && frames=4
  for _ in $(seq $runs); do
    line=$(pathtracer -i "$sponza_obj" "${pt_camera[@]}" "${pt_light[@]}" --spp 1 \
             --max-path-length 8 --benchmark 2 $frames 2>&1)
    fps=$(awk '/^BENCHMARK_RENDER_AVG /{print $2}' <<<"$line")
    mr=$(awk '/^BENCHMARK_RENDER_MRAYPS_AVG /{print $2}' <<<"$line")
    sps=$(awk -v f="$fps" 'BEGIN{print f*320*240/1e6}')
    best_pt=$(awk -v a="$best_pt" -v b="$sps" 'BEGIN{print (b>a)?b:a}')
    best_pt_rays=$(awk -v a="$best_pt_rays" -v b="$mr" 'BEGIN{print (b>a)?b:a}')
    line=$("$bin/render" "$sponza" --spp $((frames + 2)) --max-depth 8 -o "$out/s.exr" 2>&1)
    sps=$(field Msamples/s "$line"); mr=$(field Mrays/s "$line")
    best_sg=$(awk -v a="$best_sg" -v b="$sps" 'BEGIN{print (b>a)?b:a}')
    best_sg_rays=$(awk -v a="$best_sg_rays" -v b="$mr" 'BEGIN{print (b>a)?b:a}')
  done
  printf '%-34s %12s %10s\n' renderer Msamples/s Mrays/s
  printf '%-34s %12.3f %10.3f\n' "embree pathtracer --benchmark" "$best_pt" "$best_pt_rays"
  printf '%-34s %12.3f %10.3f\n' "bin/render --sampling bsdf" "$best_sg" "$best_sg_rays"
  awk -v a="$best_sg" -v b="$best_pt" 'BEGIN{r=a/b; printf "ratio %.2fx: %s (target >= 1)\n", r, (r>=1)?"ok":"MISSED"}'
  echo "(pathtracer: point light, no Russian roulette, default white-ish OBJ material, so its"
  echo " paths are longer: compare Mrays/s too. bin/render: small quad light, RR, albedo 0.5.)"
fi

# ---- precompute for the guided runs ------------------------------------
have_pipeline=1
for p in voxelize skeletonize importance render; do
  [ -x "$bin/$p" ] || have_pipeline=0
done
precompute() { # scene outdir -> outdir/importance.cache
  local scene=$1 dir=$2
  mkdir -p "$dir"
  "$bin/voxelize" "$scene" -o "$dir/medium.vdb" >/dev/null 2>&1 &&
  "$bin/skeletonize" "$dir/medium.vdb" -o "$dir/skeleton.ply" >/dev/null 2>&1 &&
  "$bin/importance" "$dir/medium.vdb" "$dir/skeleton.ply" -o "$dir/importance.cache" >/dev/null 2>&1
}

echo
echo "-- per-sample cost of guided over bsdf (same spp, runs interleaved, best of each;"
echo "   the paper paid +25%, target < +10%)"
if [ $have_pipeline = 0 ]; then
  echo "(needs bin/voxelize, bin/skeletonize, bin/importance)"
else
  printf '%-14s %-9s %10s %12s %12s %12s\n' scene sampling spp us/sample us/ray rays/sample
  for sc in "$sponza" data/corridor/corridor.json data/cornell-box/cornell-box.json; do
    [ -e "$sc" ] || continue
    name=$(basename "$sc" .json)
    if ! precompute "$sc" "$out/$name"; then echo "$name: precompute failed"; continue; fi
    spp=16; [ "$quick" = 1 ] && spp=8
    declare -A us=() ur=()
    us[bsdf]=999999; us[guided]=999999; ur[bsdf]=999999; ur[guided]=999999
    for _ in $(seq $((runs + 1))); do
      for mode in bsdf guided; do
        line=$("$bin/render" "$sc" --cache "$out/$name/importance.cache" --sampling $mode \
                 --spp $spp --max-depth 8 -o "$out/g.exr" 2>&1)
        sps=$(field Msamples/s "$line"); mr=$(field Mrays/s "$line")
        us[$mode]=$(awk -v a="${us[$mode]}" -v x="$sps" 'BEGIN{b=1/x; print (b<a)?b:a}')
        ur[$mode]=$(awk -v a="${ur[$mode]}" -v x="$mr" 'BEGIN{b=1/x; print (b<a)?b:a}')
      done
    done
    for mode in bsdf guided; do
      printf '%-14s %-9s %10s %12.4f %12.4f %12.2f\n' "$name" $mode $spp "${us[$mode]}" "${ur[$mode]}" \
        "$(awk -v a="${us[$mode]}" -v b="${ur[$mode]}" 'BEGIN{print a/b}')"
    done
    awk -v g="${us[guided]}" -v b="${us[bsdf]}" -v gr="${ur[guided]}" -v br="${ur[bsdf]}" -v n="$name" \
      'BEGIN{c=100*(g/b-1); printf "%s: guided costs %+.1f%% per sample, %+.1f%% per ray: %s (target < +10%% per sample)\n", n, c, 100*(gr/br-1), (c<10)?"ok":"MISSED"}'
  done
fi

echo
echo "-- time to error, guided vs bsdf (relMSE against a long bsdf reference; mean over seeds)"
if [ $have_pipeline = 0 ]; then
  echo "(needs bin/voxelize, bin/skeletonize, bin/importance)"
else
  seeds=3; seconds=20; ref_seconds=180
  [ "$quick" = 1 ] && { seeds=1; seconds=8; ref_seconds=40; }
  echo "   relMSE after $seconds s (mean of $seeds seeds); t_bsdf: seconds of the bsdf run; t_guided:"
  echo "   seconds guided needs to reach bsdf's final error (* = extrapolated); gain = error ratio"
  printf '%-12s %11s %11s %11s %8s %9s %8s  %s\n' scene bsdf guided skeleton t_bsdf t_guided gain target
  for sc in data/corridor/corridor.json data/cornell-box/cornell-box.json; do
    [ -e "$sc" ] || continue
    name=$(basename "$sc" .json)
    if ! precompute "$sc" "$out/$name"; then echo "$name: precompute failed"; continue; fi
    "$bin/render" "$sc" --sampling bsdf --time $ref_seconds --seed 999 -o "$out/$name/ref.exr" --quiet
    # modes interleaved, so that a change in the machine's load hits all alike
    for seed in $(seq $seeds); do
      for mode in bsdf guided skeleton; do
        "$bin/render" "$sc" --cache "$out/$name/importance.cache" --sampling $mode --time $seconds \
          --seed $seed -o "$out/$name/$mode.exr" --reference "$out/$name/ref.exr" \
          --log "$out/$name/$mode-$seed.csv" --quiet
      done
    done
    # average relMSE over seeds at each pass index (passes take about equal time)
    avg() { paste -d, "$@" | awk -F, -v n=$# 'NR>1{t=0;e=0;ok=1;for(i=0;i<n;i++){if($(4*i+1)==""){ok=0;break};t+=$(4*i+1);e+=$(4*i+4)} if(ok)print t/n, e/n}'; }
    avg "$out/$name"/bsdf-*.csv > "$out/$name/bsdf.curve"
    avg "$out/$name"/guided-*.csv > "$out/$name/guided.curve"
    avg "$out/$name"/skeleton-*.csv > "$out/$name/skeleton.curve"
    # Unbiased Monte Carlo error falls as 1/time, so the ratio of the errors
    # after equal time is the speed-up; the time guided needs to reach the
    # error bsdf ends with is shown too (extrapolated as 1/t if not reached).
    eb=$(tail -1 "$out/$name/bsdf.curve" | awk '{print $2}')
    eg=$(tail -1 "$out/$name/guided.curve" | awk '{print $2}')
    es=$(tail -1 "$out/$name/skeleton.curve" | awk '{print $2}')
    tb=$(tail -1 "$out/$name/bsdf.curve" | awk '{print $1}')
    tg=$(awk -v e="$eb" '$2<=e{print $1; exit}' "$out/$name/guided.curve")
    [ -z "$tg" ] && tg=$(tail -1 "$out/$name/guided.curve" | awk -v e="$eb" '{printf "%.2f*", $1*$2/e}')
    case $name in corridor) want=3; cmp=">= 3x";; *) want=0.95; cmp=">= 0.95x";; esac
    awk -v n="$name" -v eb="$eb" -v eg="$eg" -v es="$es" -v tb="$tb" -v tg="$tg" -v w="$want" -v c="$cmp" \
      'BEGIN{g=eb/eg; printf "%-12s %11.4g %11.4g %11.4g %8.2f %9s %7.2fx  %s: %s\n", n, eb, eg, es, tb, tg, g, c, (g>=w)?"ok":"MISSED"}'
  done
fi
