#!/usr/bin/env bash
# make bench: runs every bench/*.sh section in order; each prints its own table.
# SG_QUICK=1 (make bench-quick) asks each section for a short first look.
set -euo pipefail
cd "$(dirname "$0")/.."
echo "machine: $(nproc) cores, $(free -g | awk '/Mem:/{print $2}') GiB, $(uname -m); date: $(date -u +%F)"
for section in bench/sections/*.sh; do
  [ -e "$section" ] || continue
  echo
  echo "== $(basename "$section" .sh)"
  bash "$section"
done
