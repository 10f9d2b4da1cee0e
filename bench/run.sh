#!/usr/bin/env bash
# make bench: runs every bench/sections/*.sh in order (each prints markdown:
# its tables) and writes the report with the machine, date and commit.
#   default (make bench)          bench/report.md, images in bench/report/,
#                                 and the headline in README.md
#   SG_LONG=1 (make bench-long)   the same with longer runs (publication)
#   SG_QUICK=1 (make bench-quick) a first look: bench/out/report-quick.md and
#                                 bench/out/report-quick/; the committed
#                                 report and README are left alone
# Sections get SG_REPORT_DIR (where to put images), SG_REPORT_LINK (how the
# report links them) and SG_HEADLINE_FILE (tab-separated headline rows).
set -uo pipefail
cd "$(dirname "$0")/.."
started=$(date +%s)

if [ "${SG_QUICK:-0}" = 1 ]; then
  setting=quick command="make bench-quick" report=bench/out/report-quick.md images=bench/out/report-quick link=report-quick
elif [ "${SG_LONG:-0}" = 1 ]; then
  setting=long command="make bench-long (SG_LONG=1)" report=bench/report.md images=bench/report link=report
else
  setting=default command="make bench" report=bench/report.md images=bench/report link=report
fi

mkdir -p bench/out
stage=$(mktemp -d "$PWD/bench/out/stage.XXXXXX")
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage/images"
export SG_REPORT_DIR=$stage/images SG_REPORT_LINK=$link SG_HEADLINE_FILE=$stage/headline.tsv

cpu=$(sed -nE 's/^model name[[:space:]]*:[[:space:]]*//p' /proc/cpuinfo | head -1)
mem=$(awk '/^MemTotal:/{printf "%.1f", $2 / 1048576}' /proc/meminfo)
commit=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
[ -n "$(git status --porcelain --untracked-files=no 2>/dev/null)" ] && commit="$commit (with uncommitted changes)"
date=$(date -u '+%Y-%m-%d %H:%M UTC')
machine="$(nproc) cores, ${mem} GiB, ${cpu:-$(uname -m)}"
load=$(cut -d' ' -f1-3 /proc/loadavg)

{
  echo "# Benchmark report"
  echo
  echo "Written by \`bench/run.sh\`; do not edit by hand."
  echo
  echo "| | |"
  echo "|---|---|"
  echo "| date | $date |"
  echo "| machine | $machine |"
  echo "| load average at start | $load |"
  echo "| code | commit $commit |"
  echo "| command | \`$command\` |"
  echo "| setting | $setting |"
} >"$stage/head.md"
cat "$stage/head.md"

: >"$stage/body.md"
sections=()
for section in bench/sections/*.sh; do
  [ -e "$section" ] || continue
  name=$(basename "$section" .sh)
  sections+=("$name")
  {
    echo
    echo "## $name"
    echo
    # the section's opening comment says what it measures
    sed -n '2,/^[^#]/p' "$section" | sed -n 's/^# \{0,1\}//p' | sed -n '/^$/q;p'
    echo
  } | tee -a "$stage/body.md"
  t0=$(date +%s)
  bash "$section" | tee -a "$stage/body.md"
  status=${PIPESTATUS[0]}
  [ "$status" = 0 ] || echo "(section exited with status $status)" | tee -a "$stage/body.md"
  echo "_($name: $(( $(date +%s) - t0 )) s)_" | tee -a "$stage/body.md"
done

total=$(( $(date +%s) - started ))
{
  cat "$stage/head.md"
  echo "| duration | $((total / 60)) min $((total % 60)) s |"
  echo "| load average at the end | $(cut -d' ' -f1-3 /proc/loadavg) |"
  echo
  echo "Sections: $(for s in "${sections[@]}"; do printf '[%s](#%s) ' "$s" "$s"; done)"
  cat "$stage/body.md"
} >"$stage/report.md"

# Images first, then the report that links them; each replaced whole.
rm -rf "$images.old"
[ -d "$images" ] && mv "$images" "$images.old"
mv "$stage/images" "$images"
rm -rf "$images.old"
mv "$stage/report.md" "$report"
echo
echo "bench: report in $report ($((total / 60)) min $((total % 60)) s)"

# README headline (default and long only): the rows between the markers.
if [ "$setting" != quick ]; then
  bash bench/headline.sh README.md "$SG_HEADLINE_FILE" \
    "Latest \`$command\` ($setting setting, ${date%% *}, commit ${commit%% *}, $machine)"
fi
