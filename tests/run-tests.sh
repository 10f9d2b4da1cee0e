#!/usr/bin/env bash
# Runs every Criterion test binary given, then prints one closing line
# "tests: N passed, N failed" over all of them. Exit status 1 if any failed.
# SG_TEST_JOBS suites run at once (default: the number of cores + 1): each runs
# its own tests in parallel too, but a suite spends much of its time in a
# few long tests, and another suite fills the cores meanwhile. Each suite's
# output is kept and printed whole, in the order given, with its time.
set -u
passed=0 failed=0 status=0
export LSAN_OPTIONS="suppressions=$(cd "$(dirname "$0")" && pwd)/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
# allocator_may_return_null: an impossible allocation (a corrupt size field
# in a third-party format) must fail like it does in a release build.
# new_delete_type_mismatch: OpenImageIO 2.4's TextureSystem::destroy deletes
# its implementation through the base class with the base's size (inside
# the library; render/texture_images.cpp)
export ASAN_OPTIONS="allocator_may_return_null=1:new_delete_type_mismatch=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
# One more than the cores: a suite that waits (the farm's on its cluster,
# others on the programs they start) leaves a core to the next.
jobs_max=${SG_TEST_JOBS:-$(($(nproc 2>/dev/null || echo 2) + 1))}
work=$(mktemp -d "${TMPDIR:-/tmp}/sg-tests.XXXXXX")
trap 'rm -rf "$work"' EXIT

# Suite i writes $work/i.out, then $work/i.done: its exit status, tenths of
# seconds, and the CPU time of its processes (user, system).
(
  i=0
  for t in "$@"; do
    while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do wait -n; done
    (
      start=$(date +%s%N)
      "$t" >"$work/$i.out" 2>&1
      rc=$?
      times >"$work/$i.times" # its second line: this subshell's children, the suite's processes
      echo "$rc $((($(date +%s%N) - start) / 100000000)) $(tail -1 "$work/$i.times")" >"$work/$i.tmp"
      mv "$work/$i.tmp" "$work/$i.done"
    ) &
    i=$((i + 1))
  done
  wait
) &
launcher=$!

i=0
for t in "$@"; do
  while [ ! -e "$work/$i.done" ] && kill -0 "$launcher" 2>/dev/null; do sleep 0.2; done
  read -r rc tenths user system <"$work/$i.done" 2>/dev/null || { rc=1; tenths=0; user=?; system=?; }
  echo "== $(basename "$t") ($((tenths / 10)).$((tenths % 10)) s; CPU $user user, $system system)"
  out=$(cat "$work/$i.out" 2>/dev/null)
  printf '%s\n' "$out" | grep -vE '^\[----\] .*: (Assertion Passed|tests/)' || true
  line=$(printf '%s\n' "$out" | grep -E 'Synthesis: Tested' | tail -1)
  i=$((i + 1))
  if [ -z "$line" ]; then
    echo "$(basename "$t"): no Criterion summary (crashed? exit $rc)"
    failed=$((failed + 1)); status=1; continue
  fi
  p=$(sed -E 's/.*Passing: ([0-9]+).*/\1/' <<<"$line")
  f=$(sed -E 's/.*Failing: ([0-9]+).*/\1/' <<<"$line")
  c=$(sed -E 's/.*Crashing: ([0-9]+).*/\1/' <<<"$line")
  passed=$((passed + p)); failed=$((failed + f + c))
  [ "$rc" -ne 0 ] && status=1
done
wait "$launcher"
echo "tests: $passed passed, $failed failed"
[ "$failed" -eq 0 ] || status=1
exit $status
