# Sourced by the bench sections that need an importance cache.
# precompute_steps BIN SCENE DIR [RESOLUTION]: voxelize, skeletonize and
# importance of BIN's build into DIR (medium.vdb, skeleton.ply,
# importance.cache), their output in DIR/precompute.log; false when a step
# fails (the log's last line says why).
precompute_steps() {
  local bin=$1 scene=$2 dir=$3 res=()
  [ -n "${4:-}" ] && res=(--resolution "$4")
  mkdir -p "$dir"
  "$bin/voxelize" "$scene" "${res[@]}" -o "$dir/medium.vdb" >"$dir/precompute.log" 2>&1 &&
    "$bin/skeletonize" "$dir/medium.vdb" -o "$dir/skeleton.ply" >>"$dir/precompute.log" 2>&1 &&
    "$bin/importance" "$dir/medium.vdb" "$dir/skeleton.ply" -o "$dir/importance.cache" >>"$dir/precompute.log" 2>&1
}
