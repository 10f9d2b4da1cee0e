#!/usr/bin/env bash
# Renders a scene in N shards on a Slurm cluster (or on this machine) and
# merges them into one image.
#
#   scripts/slurm-render.sh SCENE --shards N --out DIR [options] [-- RENDER_OPTIONS]
#   scripts/slurm-render.sh --resume DIR [--wait]
#
# On Slurm (a controller answers `scontrol ping`, or --slurm) three submissions:
#   1. the precompute (voxelize, skeletonize, importance into DIR/; for a
#      mode that learns, its training into DIR/NAME.field), one job;
#   2. the shards, a job array 0..N-1 that waits for it (afterok): task K
#      runs `render SCENE --cache DIR/importance.cache [--field DIR/NAME.field]
#      --shard K/N` into
#      DIR/shards/NAME-K.exr;
#   3. the merge, after the whole array (afterok): bin/merge into
#      DIR/NAME.exr and DIR/NAME.png.
# Every job is requeued if its node fails; a shard's pixels depend only on
# (seed, shard, pass, pixel), so a rerun writes the same image, and render
# writes its EXR under a temporary name renamed when complete, so a killed
# shard leaves nothing behind. --resume DIR submits again the shards whose
# EXR is missing (after scancel, a time limit, a dead node) and the merge.
# Where no Slurm controller answers (Slurm installed but not configured, or
# not installed), or with --local, the same steps run here, one after the
# other, with the same outputs; a line says so unless --local asked for it.
#
# DIR must be on storage every node sees: the cache is memory-mapped
# read-only by every shard from there. RENDER_OPTIONS go to every shard
# (--spp is the whole render's: shard K renders passes K, K+N, ...;
# --sampling bsdf or openpgl need no cache: render --describe says; the
# modes that learn, guided and openpgl, train once and every shard renders
# with the same frozen field, so N shards are as good as one process;
# --training-passes N goes to that training alone).
#
# Options:
#   --name NAME          output name (default: the scene file's name)
#   --cpus-per-shard C   cores per shard (default 1; render --threads C)
#   --sbatch "ARGS"      more sbatch arguments for every job (partition, time limit...)
#   --local              run here even where a Slurm controller answers
#   --slurm              submit to Slurm, or fail (exit 1, nothing written) if no controller answers
#   --wait               on Slurm: return when the merge has ended (exit 1 if it failed)
#   --bin DIR            the programs (default: bin/ beside this script)
set -uo pipefail

here=$(cd "$(dirname "$0")" && pwd)
self="$here/$(basename "$0")"
die() { echo "slurm-render: $*" >&2; exit 1; }
usage() { sed -n '2,/^set /p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; }

# ---- the steps, as the jobs run them: slurm-render.sh --step STEP DIR [K] ----
run_step() {
  local step=$1 dir=$2
  # shellcheck source=/dev/null
  source "$dir/farm.env" || die "$dir/farm.env: cannot read the render's settings"
  : "${learns:=0}" # a render set up before fields
  case $step in
    precompute)
      if [ "$needs_cache" = 1 ]; then
        local key
        key=$("$bin/voxelize" "$scene" --key) || exit 1
        if [ "$key" = "$(cat "$dir/geometry.key" 2>/dev/null)" ] && [ -e "$dir/importance.cache" ]; then
          echo "slurm-render: precompute: $dir/importance.cache is up to date"
        else
          # the job has its node to itself (sbatch --exclusive below): every core
          local cores=()
          [ -n "${SLURM_CPUS_ON_NODE:-}" ] && cores=(--threads "$SLURM_CPUS_ON_NODE")
          "$bin/voxelize" "$scene" -o "$dir/medium.vdb" "${cores[@]}" --quiet &&
            "$bin/skeletonize" "$dir/medium.vdb" -o "$dir/skeleton.ply" "${cores[@]}" --quiet &&
            "$bin/importance" "$dir/medium.vdb" "$dir/skeleton.ply" -o "$dir/importance.cache" "${cores[@]}" \
              --quiet || exit 1
          printf '%s\n' "$key" >"$dir/geometry.key"
        fi
      fi
      [ "$learns" = 1 ] || exit 0
      # a mode that learns: its training once, here; every shard renders
      # with the field frozen, as one process would (render --field-out)
      local cache=() train_options=() i
      [ "$needs_cache" = 1 ] && cache=(--cache "$dir/importance.cache")
      for ((i = 0; i < ${#render_options[@]}; i++)); do
        case ${render_options[$i]} in
          --spp|--time) i=$((i + 1)) ;; # the render's, not the training's
          *) train_options+=("${render_options[$i]}") ;;
        esac
      done
      local threads=()
      [ -n "${SLURM_CPUS_ON_NODE:-}" ] && threads=(--threads "$SLURM_CPUS_ON_NODE")
      "$bin/render" "$scene" "${cache[@]}" "${train_options[@]}" "${threads[@]}" --field-out "$dir/$name.field" \
        -o "$dir/$name-training.exr" --quiet || exit 1
      ;;
    shard)
      local k=${3:-${SLURM_ARRAY_TASK_ID:-}}
      [ -n "$k" ] || die "shard: no shard index (SLURM_ARRAY_TASK_ID)"
      local cache=() field=()
      [ "$needs_cache" = 1 ] && cache=(--cache "$dir/importance.cache")
      [ "$learns" = 1 ] && field=(--field "$dir/$name.field")
      local shard_options=() i
      for ((i = 0; i < ${#render_options[@]}; i++)); do
        case ${render_options[$i]} in
          --training-passes) i=$((i + 1)) ;; # the training's, not the render's
          *) shard_options+=("${render_options[$i]}") ;;
        esac
      done
      # on a node: the cores Slurm gave the task; here: every core
      local threads=(--threads "${SLURM_CPUS_PER_TASK:-$cpus}")
      [ -n "${SG_FARM_LOCAL:-}" ] && threads=()
      exec "$bin/render" "$scene" "${cache[@]}" "${field[@]}" "${shard_options[@]}" --shard "$k/$shards" \
        "${threads[@]}" -o "$dir/shards/$name-$k.exr" --quiet
      ;;
    merge)
      local files=()
      for ((k = 0; k < shards; k++)); do files+=("$dir/shards/$name-$k.exr"); done
      exec "$bin/merge" "${files[@]}" -o "$dir/$name.exr" --png "$dir/$name.png"
      ;;
    *) die "unknown step '$step'" ;;
  esac
}

if [ "${1:-}" = --step ]; then
  shift
  run_step "$@"
  exit $?
fi

# ---- submission ----
scene= shards= out= name= cpus=1 extra_sbatch= where=auto wait=0 resume= bin="$here/../bin"
render_options=()
while [ $# -gt 0 ]; do
  case $1 in
    -h|--help) usage; exit 0 ;;
    --shards) shards=${2:-}; shift 2 ;;
    --out) out=${2:-}; shift 2 ;;
    --name) name=${2:-}; shift 2 ;;
    --cpus-per-shard) cpus=${2:-}; shift 2 ;;
    --sbatch) extra_sbatch=${2:-}; shift 2 ;;
    --local|--slurm)
      [ $where = auto ] || [ $where = "${1#--}" ] || { echo "slurm-render: --local and --slurm: one or the other, please" >&2; exit 2; }
      where=${1#--}; shift ;;
    --wait) wait=1; shift ;;
    --resume) resume=${2:-}; shift 2 ;;
    --bin) bin=${2:-}; shift 2 ;;
    --) shift; render_options=("$@"); break ;;
    -*) echo "slurm-render: $1: unknown option (see --help)" >&2; exit 2 ;;
    *) [ -z "$scene" ] || { echo "slurm-render: $1: only one scene, please" >&2; exit 2; }; scene=$1; shift ;;
  esac
done

# Where the shards run: on Slurm where its controller answers, else here.
# sbatch alone proves nothing: Debian's slurm-wlm installs it on machines
# with no cluster, where it dies on the missing configuration.
use_slurm=0
choose_where() {
  [ $where = local ] && return 0
  local why=
  if ! command -v sbatch >/dev/null 2>&1 || ! command -v scontrol >/dev/null 2>&1; then
    why="Slurm is not installed (no sbatch, scontrol)"
  else
    local answer status
    answer=$(timeout 5 scontrol ping 2>&1); status=$?
    if [[ "$answer" == *" is UP"* ]]; then
      use_slurm=1
      return 0
    fi
    if [ $status = 124 ]; then
      why="no Slurm controller answers (scontrol ping: no answer in 5 s)"
    else
      # its last line but the banner says why: "Slurmctld(primary) at HOST is
      # DOWN", "scontrol: fatal: Could not establish a configuration source"
      answer=$(printf '%s\n' "$answer" | grep -v '^\*' | grep . | tail -1)
      why="no Slurm controller answers (scontrol ping: ${answer#scontrol: })"
    fi
  fi
  [ $where = slurm ] && die "--slurm: $why"
  echo "slurm-render: $why: running the $shards shards here" >&2
}

if [ -n "$resume" ]; then
  dir=$(cd "$resume" 2>/dev/null && pwd) || die "$resume: no such directory"
  [ -r "$dir/farm.env" ] || die "$dir: not a render farm directory (no farm.env)"
  # shellcheck source=/dev/null
  source "$dir/farm.env"
  choose_where
else
  [ -n "$scene" ] || { echo "slurm-render: no scene given (see --help)" >&2; exit 2; }
  [[ "$shards" =~ ^[1-9][0-9]*$ ]] || { echo "slurm-render: --shards N: a positive integer, please" >&2; exit 2; }
  [ -n "$out" ] || { echo "slurm-render: no --out DIR given" >&2; exit 2; }
  [[ "$cpus" =~ ^[1-9][0-9]*$ ]] || { echo "slurm-render: --cpus-per-shard C: a positive integer, please" >&2; exit 2; }
  [ -r "$scene" ] || die "$scene: cannot read the scene"
  bin=$(cd "$bin" 2>/dev/null && pwd) || die "$bin: no such directory (run make first)"
  for p in voxelize skeletonize importance render merge; do
    [ -x "$bin/$p" ] || die "$bin/$p: not built (run make)"
  done
  scene=$(cd "$(dirname "$scene")" && pwd)/$(basename "$scene")
  [ -n "$name" ] || name=$(basename "${scene%.*}")
  # whether the mode needs the precompute: render says (--describe); with
  # no --sampling, the mode render picks when it is given a cache
  mode_filter='"default_with_cache": true'
  for ((i = 0; i < ${#render_options[@]}; i++)); do
    if [ "${render_options[$i]}" = --sampling ]; then
      mode_filter="\"name\": \"${render_options[$((i + 1))]:-}\""
    fi
    case ${render_options[$i]} in
      --cache|--shard|-o|--output|--png|--threads|--reference|--log)
        die "${render_options[$i]}: set by this script, not a render option to pass" ;;
    esac
  done
  mode=$("$bin/render" --describe | grep -F "$mode_filter") || die "--sampling: not a sampling mode of $bin/render (${mode_filter})"
  needs_cache=0 learns=0
  case $mode in *'"uses_cache": true'*) needs_cache=1 ;; esac
  case $mode in *'"learns": true'*) learns=1 ;; esac
  choose_where
  mkdir -p "$out/shards" "$out/logs" || die "$out: cannot create it"
  dir=$(cd "$out" && pwd)
  # a new render in an old directory: its shards would not merge
  rm -f "$dir/shards/$name"-*.exr "$dir/$name.exr" "$dir/$name.png" "$dir/$name.field"
  {
    printf 'scene=%q\nbin=%q\nshards=%q\nname=%q\ncpus=%q\nneeds_cache=%q\nlearns=%q\nextra_sbatch=%q\n' \
      "$scene" "$bin" "$shards" "$name" "$cpus" "$needs_cache" "$learns" "$extra_sbatch"
    printf 'render_options=('
    printf '%q ' "${render_options[@]}"
    printf ')\n'
  } >"$dir/farm.env.new" && mv "$dir/farm.env.new" "$dir/farm.env" || die "$dir/farm.env: cannot write it"
fi

if [ $use_slurm = 0 ]; then
  started=$(date +%s%N)
  [ -n "$resume" ] || SG_FARM_LOCAL=1 bash "$self" --step precompute "$dir" || die "precompute failed"
  for ((k = 0; k < shards; k++)); do
    [ -e "$dir/shards/$name-$k.exr" ] && continue
    [ -t 2 ] && printf '\rslurm-render: shard %d of %d' "$((k + 1))" "$shards" >&2
    SG_FARM_LOCAL=1 bash "$self" --step shard "$dir" "$k" >"$dir/logs/shard-$k.out" 2>&1 ||
      die "shard $k failed: $(tail -1 "$dir/logs/shard-$k.out")"
  done
  [ -t 2 ] && printf '\r\033[K' >&2
  bash "$self" --step merge "$dir" || die "merge failed"
  echo "slurm-render: $dir/$name.exr and $name.png from $shards shards, here (no Slurm), in $(( ($(date +%s%N) - started) / 1000000 )) ms"
  exit 0
fi

# shellcheck disable=SC2206
extra=($extra_sbatch)
submit() { sbatch --parsable --requeue "${extra[@]}" "$@" | cut -d';' -f1; }
dependency=()
if [ -z "$resume" ]; then
  pre=$(submit --exclusive --job-name "$name-precompute" --output "$dir/logs/precompute-%j.out" \
    --wrap "bash $(printf %q "$self") --step precompute $(printf %q "$dir")") || die "sbatch failed (precompute)"
  [ -n "$pre" ] || die "sbatch gave no job id"
  dependency=(--dependency "afterok:$pre" --kill-on-invalid-dep=yes)
  todo="0-$((shards - 1))"
else
  todo=
  for ((k = 0; k < shards; k++)); do
    [ -e "$dir/shards/$name-$k.exr" ] || todo+="${todo:+,}$k"
  done
fi
if [ -n "$todo" ]; then
  array=$(submit "${dependency[@]}" --job-name "$name-shards" --array "$todo" --cpus-per-task "$cpus" \
    --output "$dir/logs/shard-%a-%A.out" \
    --wrap "bash $(printf %q "$self") --step shard $(printf %q "$dir")") || die "sbatch failed (shards)"
  dependency=(--dependency "afterok:$array" --kill-on-invalid-dep=yes)
fi
merge=$(submit "${dependency[@]}" --job-name "$name-merge" --output "$dir/logs/merge-%j.out" \
  --wrap "bash $(printf %q "$self") --step merge $(printf %q "$dir")") || die "sbatch failed (merge)"
echo "slurm-render: submitted${pre:+ precompute $pre,}${array:+ shards $array (array $todo),} merge $merge:" \
  "$dir/$name.exr when it ends (squeue to watch; logs in $dir/logs/)"
echo "$merge" >"$dir/merge.jobid"

if [ $wait = 1 ]; then
  # squeue answers faster than sbatch --wait polls
  while squeue -h -j "$merge" 2>/dev/null | grep -q .; do sleep 0.5; done
  [ -e "$dir/$name.exr" ] || die "the merge job $merge ended without $dir/$name.exr (see $dir/logs/)"
  echo "slurm-render: $dir/$name.exr and $name.png"
fi
