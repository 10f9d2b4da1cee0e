#!/usr/bin/env bash
# Installs the Debian packages the toolchain needs, but only when a check
# finds one missing (so it is cheap to call before every test run).
set -euo pipefail

# package : what proves it is installed (a header or a command)
checks=(
  "build-essential:/usr/bin/make"
  "pkg-config:/usr/bin/pkg-config"
  "libembree-dev:/usr/include/embree3/rtcore.h"
  "libopenvdb-dev:/usr/include/openvdb/openvdb.h"
  "libboost-dev:/usr/include/boost/version.hpp"
  "libtbb-dev:/usr/include/tbb/tbb.h"
  "libopenimageio-dev:/usr/include/OpenImageIO/imageio.h"
  "libopenexr-dev:/usr/include/OpenEXR/ImfInputFile.h"
  "libassimp-dev:/usr/include/assimp/cimport.h"
  "libcjson-dev:/usr/include/cjson/cJSON.h"
  "libexpat1-dev:/usr/include/expat.h"
  "zlib1g-dev:/usr/include/zlib.h"
  "libcriterion-dev:/usr/include/criterion/criterion.h"
  "libopenvdb-tools:/usr/bin/vdb_print"
  "openimageio-tools:/usr/bin/idiff"
  "fonts-dejavu-core:/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"
  "slurm-wlm:/usr/sbin/slurmctld"
  "munge:/usr/sbin/munged"
)
if [ "${SG_WITH_OPENPGL:-0}" = 1 ]; then
  checks+=("cmake:/usr/bin/cmake" "ninja-build:/usr/bin/ninja")
fi
if [ "${SG_WITH_BENCH_TOOLS:-0}" = 1 ]; then
  checks+=("embree-tools:/usr/bin/pathtracer" "python3:/usr/bin/python3" "time:/usr/bin/time" "gnuplot-nox:/usr/bin/gnuplot")
fi

missing=()
for entry in "${checks[@]}"; do
  pkg=${entry%%:*}
  path=${entry#*:}
  [ -e "$path" ] || missing+=("$pkg")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "install-deps: installing ${missing[*]}" >&2
if [ "$(id -u)" -eq 0 ]; then
  sudo=()
elif command -v sudo >/dev/null 2>&1; then
  sudo=(sudo)
else
  echo "install-deps: missing packages (${missing[*]}) and neither root nor sudo" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -qq
"${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
