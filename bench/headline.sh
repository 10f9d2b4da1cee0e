#!/usr/bin/env bash
# bench/headline.sh README ROWS CAPTION: rewrites what lies between the lines
# <!-- bench-headline:begin --> and <!-- bench-headline:end --> of README
# with CAPTION and a table of ROWS (60-convergence's headline rows: scene,
# image, relMSE level, bsdf s, guided s, guided speed-up, skeleton speed-up,
# and where the peer ran, openpgl s, openpgl speed-up, guided over openpgl;
# tab-separated). The openpgl columns are there when any row has them.
# Atomic (temporary file, then mv) and idempotent (the same input gives the
# same file); README is left alone when a marker is missing or there are no
# rows.
set -uo pipefail
readme=$1 rows=$2 caption=$3
begin='<!-- bench-headline:begin -->' end='<!-- bench-headline:end -->'
if [ "$(grep -cxF "$begin" "$readme")" != 1 ] || [ "$(grep -cxF "$end" "$readme")" != 1 ]; then
  echo "bench: $readme: want one line $begin and one line $end; not updated"; exit 1
fi
if [ ! -s "$rows" ]; then
  echo "bench: no convergence results; $readme not updated"; exit 1
fi
block=$(mktemp)
trap 'rm -f "$block"' EXIT
{
  echo "$caption; the full report with plots and equal-time crops is [bench/report.md](bench/report.md)."
  echo "Seconds of rendering to reach a relMSE level (\`bsdf\`'s error at the end of its run, rounded up)"
  echo "and the speed-up over \`bsdf\` = bsdf seconds / mode seconds (> 1: faster than"
  if [ "$(awk -F'\t' 'NF >= 10 {n++} END {print n + 0}' "$rows")" -gt 0 ]; then
    echo "bsdf; ~: extrapolated as 1/t; \`skeleton\` is the paper's biased rule; \`openpgl\` is Open PGL,"
    echo "the state of the art peer, in our path tracer; guided over openpgl = openpgl seconds / guided seconds)."
    echo
    echo "| scene | image | relMSE level | bsdf s | guided s | openpgl s | guided speed-up | openpgl speed-up | guided over openpgl | skeleton speed-up |"
    echo "|---|---|---|---|---|---|---|---|---|---|"
    awk -F'\t' 'NF >= 7 {
      if (NF < 10) { $8 = "-"; $9 = "-"; $10 = "-" }
      printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5, $8, $6, $9, $10, $7
    }' "$rows"
  else
    echo "bsdf; ~: extrapolated as 1/t; \`skeleton\` is the paper's biased rule)."
    echo
    echo "| scene | image | relMSE level | bsdf s | guided s | guided speed-up | skeleton speed-up |"
    echo "|---|---|---|---|---|---|---|"
    awk -F'\t' 'NF >= 7 {printf "| %s | %s | %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5, $6, $7}' "$rows"
  fi
} >"$block"
tmp=$(dirname "$readme")/.$(basename "$readme").tmp.$$
if awk -v b="$begin" -v e="$end" -v f="$block" '
     $0 == b { print; while ((getline l < f) > 0) print l; skip = 1; next }
     $0 == e { skip = 0 }
     !skip' "$readme" >"$tmp" && mv "$tmp" "$readme"; then
  echo "bench: $readme headline updated"
else
  rm -f "$tmp"; echo "bench: $readme: headline not written"; exit 1
fi
