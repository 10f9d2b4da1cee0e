#!/usr/bin/env bash
# Builds Open PGL (the path guiding peer, see ../shared/peers/README.md) once
# into build/openpgl/, with its radiance caches (OPENPGL_EF_RADIANCE_CACHES:
# what render --openpgl-mode ris and Open PGL's guided roulette need), and
# rebuilds it only when its tarball or these options change.
#   OPENPGL_TARBALL=path   the source tarball (default ../shared/peers/openpgl-0.7.1.tar.gz)
#   OPENPGL_DIR=prefix     an installed Open PGL (include/openpgl, lib/libopenpgl.so):
#                          nothing is built, the Makefile links that one
# Prints nothing when the cached build is current; exits non-zero, saying
# why in one line, when there is nothing to build from.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ -n "${OPENPGL_DIR:-}" ]; then
  if [ -e "$OPENPGL_DIR/include/openpgl/openpgl.h" ]; then
    if ! grep -qs '^#define OPENPGL_RADIANCE_CACHES' "$OPENPGL_DIR/include/openpgl/defines.h"; then
      echo "build-openpgl: $OPENPGL_DIR was built without OPENPGL_EF_RADIANCE_CACHES: openpgl's guided roulette is off (the albedo roulette runs)" >&2
    fi
    exit 0
  fi
  echo "build-openpgl: OPENPGL_DIR=$OPENPGL_DIR has no include/openpgl/openpgl.h" >&2
  exit 1
fi

tarball=${OPENPGL_TARBALL:-../shared/peers/openpgl-0.7.1.tar.gz}
if [ ! -r "$tarball" ]; then
  echo "build-openpgl: $tarball: not found (set OPENPGL_TARBALL= or OPENPGL_DIR=)" >&2
  exit 1
fi
root=$PWD/build/openpgl
# the options the library is built with: a build made with others is redone
options="-DOPENPGL_EF_RADIANCE_CACHES=ON"
stamp=$root/build.stamp
sum="$(sha256sum "$tarball" | cut -d' ' -f1) $options"
if [ -e "$stamp" ] && [ "$(cat "$stamp")" = "$sum" ] && [ -e "$root/install/lib/libopenpgl.so" ]; then
  exit 0
fi

SG_WITH_OPENPGL=1 bash scripts/install-deps.sh
echo "build-openpgl: building Open PGL from $tarball into build/openpgl (a few minutes)" >&2
rm -rf "$root"
mkdir -p "$root/src"
tar -xzf "$tarball" -C "$root/src"
src=$(find "$root/src" -mindepth 1 -maxdepth 1 -type d | head -n 1)
log=$root/build.log
# Release, no tests or tools: the library and its headers, nothing else.
if ! cmake -S "$src" -B "$root/cmake" -G Ninja -DCMAKE_BUILD_TYPE=Release \
       -DCMAKE_INSTALL_PREFIX="$root/install" -DCMAKE_INSTALL_LIBDIR=lib \
       -DOPENPGL_BUILD_STATIC=OFF -DOPENPGL_BUILD_TOOLS=OFF $options >"$log" 2>&1 ||
   ! ninja -C "$root/cmake" -j"$(nproc)" install >>"$log" 2>&1; then
  echo "build-openpgl: the build failed; its log: $log" >&2
  exit 1
fi
echo "$sum" >"$stamp"
echo "build-openpgl: done, build/openpgl/install/" >&2
