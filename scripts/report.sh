#!/usr/bin/env bash
# Regenerates the speed-versus-error report (docs/report.md): builds `ridge` (Release), writes the
# 1025 x 1025 noise field with `ridge report --write-noise-field`, fetches the real DEM (elev.tif of
# Debian's r-cran-terra, without installing R), runs `ridge report` once over every scene, path,
# setting and mode, then plots with gnuplot.
# Usage: bash scripts/report.sh [OUT_DIR]   (default docs/benchmarks/report; inputs in build/report-data)
#        RIDGE=build/x/module/ridge bash scripts/report.sh   (use an already built Release ridge)
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
cd "$RIDGELINE_ROOT"
out=${1:-docs/benchmarks/report}
data=build/report-data
mkdir -p "$out" "$data"
ensure_packages "${RIDGELINE_PACKAGES[@]}" "${RIDGELINE_REPORT_PACKAGES[@]}"
ridge=${RIDGE:-}
if [ -z "$ridge" ]; then  # the report needs only `ridge`: build that target, not the whole tree
  build_release ridge > /dev/null
  ridge=$RIDGELINE_RELEASE_DIR/module/ridge
fi
build_s=$SECONDS

[ -f "$data/noise1025.png" ] || "$ridge" report --write-noise-field "$data"

dem=$data/terra/usr/lib/R/site-library/terra/ex/elev.tif
if [ ! -f "$dem" ]; then
  (cd "$data" && rm -f r-cran-terra_*.deb && { apt-get download r-cran-terra > /dev/null 2>&1 ||
     { apt-get update -qq && apt-get download r-cran-terra > /dev/null; }; } &&
   dpkg -x r-cran-terra_*.deb terra)
fi

{
  echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)," \
       "$(awk '/MemTotal/ {printf "%.1f GB", $2 / 1048576}' /proc/meminfo)"
  echo "date: $(date -u +%Y-%m-%dT%H:%MZ), commit $(git rev-parse --short HEAD), binary $ridge"
  echo "load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "uptime at start: $(uptime)"
  echo "build (ridge only, before the start): ${build_s} s"
} > "$out/machine.txt"
"$ridge" report --noise "$data/noise1025.png" --dem "$dem" --out "$out" --work "$data/hard"
python3 docs/benchmarks/report/plots.py "$out"
{
  echo "load average at end: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "uptime at end: $(uptime)"
  echo "wall time of scripts/report.sh: ${SECONDS} s (build ${build_s} s, then ridge report and plots)"
} >> "$out/machine.txt"
echo "wrote $out/report.json, report.csv, summary.md, plots/*.png"
