#!/usr/bin/env bash
# ROAM (frame-coherent RoamView) against the stateless SOAR refinement, like for like, on the
# 1025 x 1025 value-noise field and its 360-frame circular flyover (written by
# `ridge report --write-noise-field`): per row the two runs alternate ROUNDS times in one script
# run, so that a change in the machine's load hits both; each run's figures are medians over the
# path, and the row reports the median over rounds of each figure and of the per-round ratio.
#
#   ROAM: update + output (the update, which patches the per-patch buffers in place, plus taking
#         the dirty ranges an engine uploads)
#   SOAR: refinement + emission of the whole triangle strip, from scratch every frame
#
# Rows: at equal whole-landscape triangle counts (--triangles N --threshold 0: ROAM's cap; SOAR's
# one kappa whose median count over the path is closest to N), and both at --threshold 1. Each
# row twice: with nothing between frames (warm caches) and with 64 MiB of other memory read and
# written before each frame (--flush-mb 64: the rest of a game's frame evicting the terrain).
# Usage: scripts/bench_roam_vs_soar.sh [OUT.json]   (default docs/benchmarks/roam_vs_soar.json)
# ROUNDS=N (default 3).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
cd "$RIDGELINE_ROOT"
out=${1:-docs/benchmarks/roam_vs_soar.json}
rounds=${ROUNDS:-3}
work=build/bench
mkdir -p "$work" "$(dirname "$out")"
ensure_packages "${RIDGELINE_PACKAGES[@]}" python3
build_release ridge bench_roam_core > /dev/null
ridge=build/release/module/ridge
[ -f "$work/noise1025.png" ] && [ -f "$work/noise1025_circle.json" ] ||
  "$ridge" report --write-noise-field "$work"
noise=(--heightmap "$work/noise1025.png" --spacing 1 --height-scale 0.005
       --path "$work/noise1025_circle.json" --warmup 60 --error-every 10)

rm -f "$work/vs_soar.jsonl"
run() {  # ROW FLUSH_MB MODE ROUND ARGS...
  local row=$1 flush=$2 mode=$3 round=$4; shift 4
  local f="$work/vs_soar_${row}_${flush}_${mode}_${round}.json"
  "$ridge" bench lod "${noise[@]}" --mode "$mode" --flush-mb "$flush" "$@" --json "$f" ||
    { echo "bench_roam_vs_soar.sh: $row $mode failed" >&2; exit 1; }
  python3 - "$f" "$row" "$flush" "$mode" "$round" "$(cut -d' ' -f1 /proc/loadavg)" \
    >> "$work/vs_soar.jsonl" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))["summary"]
print(json.dumps({"row": sys.argv[2], "flush_mb": float(sys.argv[3]), "mode": sys.argv[4],
                  "round": int(sys.argv[5]), "load": float(sys.argv[6]), "summary": s}))
PY
}
for row in n5250 n20800 n53000 t1; do
  case $row in
    t1) args=(--threshold 1) ;;
    *) args=(--triangles "${row#n}" --threshold 0) ;;
  esac
  for flush in 0 64; do
    for ((k = 0; k < rounds; ++k)); do
      run "$row" "$flush" coherent "$k" "${args[@]}"
      run "$row" "$flush" soar "$k" "${args[@]}"
    done
  done
done

# The same comparison frame by frame in one process (tests/bench/bench_roam_core.cpp): ROAM's
# update + output and SOAR's refine + emit alternate on every frame, with nothing else between
# frames (warm) and with 64 MiB of other memory read and written between frames (the rest of an
# engine's frame evicting the terrain's data).
core=build/release/tests/bench/bench_roam_core
rm -f "$work/vs_soar_core.jsonl"
if [ -x "$core" ]; then
  for row in n5250 n20800 n53000 t1; do
    case $row in
      t1) cargs=(--threshold 1) ;;
      *) cargs=(--triangles "${row#n}") ;;
    esac
    for flush in 0 64; do
      "$core" "${cargs[@]}" --rounds "$rounds" --flush-mb "$flush" |
        python3 -c "import json,sys; d=json.load(sys.stdin); d['row']='$row'; d['load']=$(cut -d' ' -f1 /proc/loadavg); print(json.dumps(d))" \
        >> "$work/vs_soar_core.jsonl"
    done
  done
fi
export CORE_JSONL=$work/vs_soar_core.jsonl

python3 - "$work/vs_soar.jsonl" "$out" "$rounds" <<'PY'
import json, statistics, sys
runs = [json.loads(l) for l in open(sys.argv[1])]
med = statistics.median
rows = []
for row, flush in dict.fromkeys((r["row"], r["flush_mb"]) for r in runs):
    c = [r for r in runs if (r["row"], r["flush_mb"]) == (row, flush) and r["mode"] == "coherent"]
    s = [r for r in runs if (r["row"], r["flush_mb"]) == (row, flush) and r["mode"] == "soar"]
    def m(rs, key):
        v = [r["summary"][key] for r in rs if r["summary"].get(key) is not None]
        return med(v) if v else None
    ratio_wall = [b["summary"]["update_ms_median"] / a["summary"]["update_plus_output_ms_median"]
                  for a, b in zip(c, s)]
    ratio_cpu = [b["summary"]["update_cpu_ms_median"] /
                 a["summary"]["update_plus_output_cpu_ms_median"] for a, b in zip(c, s)]
    rows.append({
        "row": row,
        "flush_mb": flush,
        "roam_update_plus_output_ms": m(c, "update_plus_output_ms_median"),
        "roam_update_plus_output_cpu_ms": m(c, "update_plus_output_cpu_ms_median"),
        "roam_update_ms": m(c, "update_ms_median"),
        "roam_output_ms": m(c, "output_ms_median"),
        "soar_refine_and_emit_ms": m(s, "update_ms_median"),
        "soar_refine_and_emit_cpu_ms": m(s, "update_cpu_ms_median"),
        "soar_refine_only_ms": m(s, "refine_only_ms_median"),
        "soar_over_roam_wall": med(ratio_wall),
        "soar_over_roam_cpu": med(ratio_cpu),
        "roam_triangles": m(c, "triangles_median"),
        "soar_triangles": m(s, "triangles_median"),
        "roam_triangles_in_view": m(c, "triangles_in_view_median"),
        "soar_triangles_in_view": m(s, "triangles_in_view_median"),
        "roam_rms_error_m": m(c, "rms_error_median"),
        "soar_rms_error_m": m(s, "rms_error_median"),
        "roam_max_screen_error_px": m(c, "max_screen_error_px_median"),
        "soar_max_screen_error_px": m(s, "max_screen_error_px_median"),
        "roam_upload_bytes": m(c, "upload_bytes_median"),
        "soar_upload_bytes": m(s, "upload_bytes_median"),
        "roam_changes_per_frame": m(c, "changes_per_frame_median"),
        "roam_view_bytes_per_triangle": m(c, "view_bytes_per_triangle"),
        "roam_output_bytes_per_triangle": m(c, "output_bytes_per_triangle"),
        "load_average": [r["load"] for r in c + s],
    })
json.dump({"command": "scripts/bench_roam_vs_soar.sh", "rounds": int(sys.argv[3]),
           "rows": rows}, open(sys.argv[2], "w"), indent=1)
import os
core = os.environ.get("CORE_JSONL")
if core and os.path.exists(core):
    d = json.load(open(sys.argv[2]))
    d["bench_roam_core"] = [json.loads(l) for l in open(core)]
    json.dump(d, open(sys.argv[2], "w"), indent=1)
for r in rows:
    print(f'{r["row"]:>7} flush {r["flush_mb"]:>3g} MiB: ROAM {r["roam_update_plus_output_ms"]:.3f} ms, SOAR '
          f'{r["soar_refine_and_emit_ms"]:.3f} ms, SOAR/ROAM {r["soar_over_roam_wall"]:.2f} (wall) '
          f'{r["soar_over_roam_cpu"]:.2f} (cpu); triangles {r["roam_triangles"]:.0f} / '
          f'{r["soar_triangles"]:.0f}; RMS {r["roam_rms_error_m"]:.3f} / {r["soar_rms_error_m"]:.3f} m')
PY
[ -f "$work/vs_soar_core.jsonl" ] && python3 - "$work/vs_soar_core.jsonl" <<'PY'
import json, sys
for l in open(sys.argv[1]):
    d = json.loads(l)
    print(f'{d["row"]:>7} flush {d["flush_mb"]:>3g} MiB: ROAM {d["roam_update_plus_output_ms_median"]:.3f} ms, '
          f'SOAR {d["soar_refine_emit_ms_median"]:.3f} ms, SOAR/ROAM {d["soar_over_roam_median_of_frame_ratios"]:.2f} '
          f'(frame by frame); triangles {d["roam_triangles_median"]:.0f} / {d["soar_triangles_median"]:.0f}')
PY
echo "wrote $out"
