#!/usr/bin/env bash
# Regenerates the benchmark figures quoted in docs/benchmarks.md: query speed and ROAM cost and
# error along camera paths, on the 1025 x 1025 value-noise field the peer figures were measured on
# (written by `ridge report --write-noise-field`) and on the built-in default terrain, with the
# stateless SOAR comparator (`bench lod --mode soar`) on the noise field in the same run.
# Usage: scripts/bench.sh [OUT_DIR]   (default docs/benchmarks; per-frame JSON goes to build/bench)
# BENCH_ONLY=lod runs only the ROAM part (lod_summary.json, tables.md).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
cd "$RIDGELINE_ROOT"
out=${1:-docs/benchmarks}
work=build/bench
mkdir -p "$out" "$work"
ensure_packages "${RIDGELINE_PACKAGES[@]}" python3
build_release ridge bench_lua > /dev/null
ridge=build/release/module/ridge

# The peers' noise field and circle path, from the project's own definition (ridgeline/scenes.h).
[ -f "$work/noise1025.png" ] && [ -f "$work/noise1025_circle.json" ] ||
  "$ridge" report --write-noise-field "$work"
noise=(--heightmap "$work/noise1025.png" --spacing 1 --height-scale 0.005)

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)" | tee "$out/machine.txt"

only=${BENCH_ONLY:-all}
if [ "$only" = all ]; then
  # Queries.
  "$ridge" bench queries --default-terrain --json "$out/queries_default.json"
  "$ridge" bench queries "${noise[@]}" --json "$out/queries_noise1025.json"
  # Lua calls (when the binding is built).
  [ -x build/release/bindings/lua/bench_lua ] && build/release/bindings/lua/bench_lua > "$out/lua.json"
fi

# ROAM along paths. Error measured every 10th frame on every vertex in view. A row that fails
# stops the script (set -e): no row is dropped silently.
lod() {  # NAME ARGS...
  local name=$1; shift
  "$ridge" bench lod "$@" --error-every 10 --json "$work/$name.json" ||
    { echo "bench.sh: row $name failed" >&2; exit 1; }
  python3 - "$work/$name.json" "$name" >> "$work/summaries.jsonl" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))["summary"]
s["name"] = sys.argv[2]
print(json.dumps(s))
PY
}
rm -f "$work/summaries.jsonl"
path=$work/noise1025_circle.json
for t in 0.5 1 2 4 8; do
  for mode in coherent rebuild soar; do
    lod "noise_${mode}_t$t" "${noise[@]}" --path "$path" --threshold "$t" --mode "$mode" --warmup 60
  done
done
for n in 5250 20800 53000; do
  for mode in coherent soar; do
    lod "noise_${mode}_n$n" "${noise[@]}" --path "$path" --triangles "$n" --mode "$mode" --warmup 60
  done
done
# The peers' SOAR settings: nu = 100, 250, 500 is a threshold of 512 / nu px on this path.
for nu in 100 250 500; do
  lod "noise_soar_nu$nu" "${noise[@]}" --path "$path" --mode soar \
    --threshold "$(python3 -c "print(512 / $nu)")" --warmup 60
done
# Time budgets on the flyover at 1 px (wall and thread-CPU percentiles).
for b in 2 0.5; do
  lod "noise_coherent_t1_budget${b}ms" "${noise[@]}" --path "$path" --threshold 1 --budget-ms "$b" \
    --warmup 60
done
for p in flyover drive fast_yaw zoom down fast_pass; do
  lod "default_${p}_t2" --default-terrain --path "tests/data/paths/$p.json" --threshold 2
done
for p in fast_yaw zoom fast_pass; do
  for b in 1 0.5; do
    lod "default_${p}_t1_budget${b}ms" --default-terrain --path "tests/data/paths/$p.json" \
      --threshold 1 --budget-ms "$b"
  done
done
python3 - "$work/summaries.jsonl" > "$out/lod_summary.json" <<'PY'
import json, sys
print(json.dumps([json.loads(l) for l in open(sys.argv[1])], indent=1))
PY
python3 docs/benchmarks/tables.py "$out" > "$out/tables.md"

[ "$only" = all ] || { echo "wrote $out/lod_summary.json, $out/tables.md"; exit 0; }

# Detail streaming (issue 4): a 100 km x 100 km world (the default terrain stretched to
# 3126 x 3126 samples at 32 m, heights x 4) with 7 detail levels (0.25 m, 1.6e11 virtual
# samples), flown over at 300 m/s, 50 m above the ground, with 2 workers, all terrain data
# (base, detail field, tiles) within 256 MiB.
"$ridge" bench detail --default-terrain --default-size 3126 --spacing 32 --height-scale 4 \
  --detail-levels 7 --terrain-budget-mb 256 --workers 2 --speed 300 --altitude 50 --prefill \
  --json "$out/detail_flight.json"
echo "wrote $out/queries_*.json, $out/lod_summary.json, $out/tables.md, $out/detail_flight.json (per-frame JSON in $work)"
