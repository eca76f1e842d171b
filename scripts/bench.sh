#!/usr/bin/env bash
# Regenerates the figures of docs/benchmarks.md from the benchmark programs' JSON (the programs
# are front ends of Ridgeline::bench, module/bench/). Parts, in the order `all` runs them:
#
#   table    the table of current figures that opens docs/benchmarks.md: ROAM (coherent, rebuild)
#            against SOAR on the 1025 x 1025 noise field's circular flyover (`ridge bench lod`,
#            the techniques' runs alternating ROUNDS times; `bench_roam_core` frame by frame),
#            collected into docs/benchmarks/current.json, then the table rewritten in place
#            (docs/benchmarks/current.py). A few minutes.
#   lod      `ridge bench lod` over thresholds, caps and time budgets on the noise field and the
#            default terrain's paths: docs/benchmarks/lod_summary.json and tables.md
#   queries  `ridge bench queries` on both terrains and bench_lua: queries_*.json, lua.json
#   detail   the 100 km detail-streaming flight: detail_flight.json (5 minutes, paced in wall time)
#
# Usage: scripts/bench.sh [PART...]   (default: all; per-frame JSON goes to build/bench)
#        ROUNDS=N scripts/bench.sh table   (default 3)
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
cd "$RIDGELINE_ROOT"
out=docs/benchmarks
work=build/bench
parts=("$@")
[ ${#parts[@]} -gt 0 ] || parts=(all)
for p in "${parts[@]}"; do
  case $p in table | lod | queries | detail | all) ;;
    *) echo "bench.sh: unknown part '$p' (table, lod, queries, detail, all)" >&2; exit 2 ;;
  esac
done
wants() { [[ " ${parts[*]} " == *" $1 "* || " ${parts[*]} " == *" all "* ]]; }

mkdir -p "$out" "$work"
ensure_packages "${RIDGELINE_PACKAGES[@]}" python3
build_release ridge bench_roam_core bench_lua > /dev/null
ridge=$RIDGELINE_RELEASE_DIR/module/ridge
core=$RIDGELINE_RELEASE_DIR/tests/bench/bench_roam_core

# The peers' noise field and circle path, from the project's own definition (ridgeline/scenes.h).
[ -f "$work/noise1025.png" ] && [ -f "$work/noise1025_circle.json" ] ||
  "$ridge" report --write-noise-field "$work"
noise=(--heightmap "$work/noise1025.png" --spacing 1 --height-scale 0.005)
circle=(--path "$work/noise1025_circle.json" --warmup 60 --error-every 10)
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)

# lod NAME ARGS...: one `ridge bench lod` run into $work/NAME.json; a failing run stops the
# script (set -e): no figure is dropped silently.
lod() {
  local name=$1; shift
  "$ridge" bench lod "$@" --json "$work/$name.json" ||
    { echo "bench.sh: run $name failed" >&2; exit 1; }
}
loads=()
note_load() { loads+=("$(cut -d' ' -f1 /proc/loadavg)"); }

if wants table; then
  t=$work/table
  rm -rf "$t" && mkdir -p "$t"
  # Rows (kept in step with docs/benchmarks/current.py): whole-landscape triangle caps (SOAR:
  # the one kappa whose median count over the path is closest), a 64 MiB flush of other memory
  # before each update (the rest of a game's frame), a 1 px threshold, a time budget.
  declare -A args=(
    [n5250]="--triangles 5250 --threshold 0" [n20800]="--triangles 20800 --threshold 0"
    [n53000]="--triangles 53000 --threshold 0"
    [n53000_flush64]="--triangles 53000 --threshold 0 --flush-mb 64"
    [t1]="--threshold 1" [t1_budget0.5]="--threshold 1 --budget-ms 0.5")
  declare -A modes=([n5250]="coherent soar" [n20800]="coherent soar" [n53000]="coherent soar"
    [n53000_flush64]="coherent soar" [t1]="coherent rebuild soar" [t1_budget0.5]="coherent")
  rows=(n5250 n20800 n53000 n53000_flush64 t1 t1_budget0.5)
  note_load
  for ((k = 1; k <= ${ROUNDS:-3}; ++k)); do
    for row in "${rows[@]}"; do
      for mode in ${modes[$row]}; do
        # shellcheck disable=SC2086
        lod "table/lod_${row}_${mode}_r$k" "${noise[@]}" "${circle[@]}" --mode "$mode" ${args[$row]}
        note_load
      done
    done
  done
  # Frame by frame in one process: ROAM's update + output and SOAR's refine + emit alternate on
  # every frame (bench_roam_core: the same frame loop).
  declare -A core_args=([n5250]="--triangles 5250" [n20800]="--triangles 20800"
    [n53000]="--triangles 53000" [n53000_flush64]="--triangles 53000 --flush-mb 64"
    [t1]="--threshold 1")
  for row in n5250 n20800 n53000 n53000_flush64 t1; do
    # shellcheck disable=SC2086
    "$core" ${core_args[$row]} --rounds "${ROUNDS:-3}" --json "$t/core_$row.json"
    note_load
  done
  dirty=$(git diff --quiet HEAD -- module bindings tests sample_game CMakeLists.txt || echo ", uncommitted changes")
  python3 - "$t/machine.json" "$(git rev-parse --short HEAD)$dirty" "$(nproc) cores ($cpu)" \
    "${loads[@]}" <<'PY'
import json, sys
json.dump({"commit": sys.argv[2], "machine": sys.argv[3],
           "load_average": [float(x) for x in sys.argv[4:]]}, open(sys.argv[1], "w"))
PY
  python3 docs/benchmarks/current.py collect "$t" "$out/current.json"
  python3 docs/benchmarks/current.py render "$out/current.json" docs/benchmarks.md
fi

if wants lod; then
  rm -f "$work/summaries.jsonl"
  summary() {  # NAME ARGS...: a run, its summary appended to summaries.jsonl
    lod "$@"
    python3 -c 'import json, sys; s = json.load(open(sys.argv[1]))["summary"]; s["name"] = sys.argv[2]; print(json.dumps(s))' \
      "$work/$1.json" "$1" >> "$work/summaries.jsonl"
  }
  for th in 0.5 1 2 4 8; do
    for mode in coherent rebuild soar; do
      summary "noise_${mode}_t$th" "${noise[@]}" "${circle[@]}" --threshold "$th" --mode "$mode"
    done
  done
  for n in 5250 20800 53000; do
    for mode in coherent soar; do
      summary "noise_${mode}_n$n" "${noise[@]}" "${circle[@]}" --triangles "$n" --mode "$mode"
    done
  done
  # The peers' SOAR settings: nu = 100, 250, 500 is a threshold of 512 / nu px on this path.
  for nu in 100 250 500; do
    summary "noise_soar_nu$nu" "${noise[@]}" "${circle[@]}" --mode soar \
      --threshold "$(python3 -c "print(512 / $nu)")"
  done
  for b in 2 0.5; do
    summary "noise_coherent_t1_budget${b}ms" "${noise[@]}" "${circle[@]}" --threshold 1 --budget-ms "$b"
  done
  for p in flyover drive fast_yaw zoom down fast_pass; do
    summary "default_${p}_t2" --default-terrain --path "tests/data/paths/$p.json" --threshold 2 \
      --error-every 10
  done
  for p in fast_yaw zoom fast_pass; do
    for b in 1 0.5; do
      summary "default_${p}_t1_budget${b}ms" --default-terrain --path "tests/data/paths/$p.json" \
        --threshold 1 --budget-ms "$b" --error-every 10
    done
  done
  python3 -c 'import json, sys; print(json.dumps([json.loads(l) for l in open(sys.argv[1])], indent=1))' \
    "$work/summaries.jsonl" > "$out/lod_summary.json"
  echo "machine: $(nproc) cores, $cpu" > "$out/machine.txt"
fi

if wants queries; then
  "$ridge" bench queries --default-terrain --json "$out/queries_default.json"
  "$ridge" bench queries "${noise[@]}" --json "$out/queries_noise1025.json"
  lua=$RIDGELINE_RELEASE_DIR/bindings/lua/bench_lua
  [ -x "$lua" ] && "$lua" > "$out/lua.json"
fi
if wants lod || wants queries; then
  python3 docs/benchmarks/tables.py "$out" > "$out/tables.md"
fi

if wants detail; then
  # A 100 km x 100 km world (the default terrain stretched to 3126 x 3126 samples at 32 m,
  # heights x 4) with 7 detail levels (0.25 m, 1.6e11 virtual samples), flown over at 300 m/s,
  # 50 m above the ground, with 2 workers, all terrain data within 256 MiB (docs/detail.md).
  "$ridge" bench detail --default-terrain --default-size 3126 --spacing 32 --height-scale 4 \
    --detail-levels 7 --terrain-budget-mb 256 --workers 2 --speed 300 --altitude 50 --prefill \
    --json "$out/detail_flight.json"
fi
echo "bench.sh: ${parts[*]} done (JSON in $out, per-frame JSON in $work)"
