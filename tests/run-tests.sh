#!/usr/bin/env bash
# Runs every Criterion test binary given, then prints one closing line
# "tests: N passed, N failed" over all of them. Exit status 1 if any failed.
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
for t in "$@"; do
  echo "== $(basename "$t")"
  out=$("$t" 2>&1); rc=$?
  printf '%s\n' "$out" | grep -vE '^\[----\] .*: (Assertion Passed|tests/)' || true
  line=$(printf '%s\n' "$out" | grep -E 'Synthesis: Tested' | tail -1)
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
echo "tests: $passed passed, $failed failed"
[ "$failed" -eq 0 ] || status=1
exit $status
