#!/usr/bin/env python3
"""Prints the markdown tables of docs/benchmarks.md from the JSON that scripts/bench.sh writes.
Usage: tables.py DIR (the folder holding lod_summary.json and queries_*.json)."""
import json, os, sys

d = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(__file__)
out = []
for name in ("queries_noise1025.json", "queries_default.json"):
    p = os.path.join(d, name)
    if not os.path.exists(p):
        continue
    q = json.load(open(p))
    out.append(f"**{name}** ({q.get('points')} points, {q.get('repetitions')} repetitions, medians)\n")
    out.append("| height | height + normal | vertical ray | slanted ray (256 cells) | sample (both normals) | bytes/sample |")
    out.append("| --- | --- | --- | --- | --- | --- |")
    out.append(f"| {q['height_ns']:.1f} ns | {q['height_normal_ns']:.1f} ns | {q['vertical_ray_ns']:.1f} ns "
               f"| {q['slanted_ray_ns']:.0f} ns | {q.get('sample_ns', float('nan')):.0f} ns | {q['bytes_per_sample']:.2f} |\n")

rows = {r["name"]: r for r in json.load(open(os.path.join(d, "lod_summary.json")))}
noise = [n for n in rows if n.startswith("noise_") and "_t" in n and "_n" not in n]
if noise:
    out.append("**Noise field, 360-frame circular flyover, coherent vs rebuild (same run)**\n")
    out.append("| threshold px | mode | update ms median | p99 | triangles | splits+merges/frame | RMS error m | max error m | max screen px | rebuild / coherent |")
    out.append("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for t in ("0.5", "1", "2", "4", "8"):
        c, r = rows.get(f"noise_coherent_t{t}"), rows.get(f"noise_rebuild_t{t}")
        for mode, s in (("coherent", c), ("rebuild", r)):
            if not s:
                continue
            ratio = f"{r['update_ms_median'] / c['update_ms_median']:.1f}x" if mode == "coherent" and c and r else ""
            out.append(f"| {t} | {mode} | {s['update_ms_median']:.3f} | {s['update_ms_p99']:.3f} | {s['triangles_median']:.0f} "
                       f"| {s['changes_per_frame_median']:.0f} | {s['rms_error_median']:.3f} | {s['max_error_median']:.2f} "
                       f"| {s['max_screen_error_px_median']:.2f} | {ratio} |")
    out.append("")
budget = [n for n in rows if n.startswith("noise_coherent_n")]
if budget:
    out.append("**Noise field flyover under a triangle cap (threshold 0: the best mesh of N triangles)**\n")
    out.append("| cap | update ms median | p99 | triangles | RMS error m | max error m |")
    out.append("| --- | --- | --- | --- | --- | --- |")
    for n in budget:
        s = rows[n]
        out.append(f"| {s['max_triangles']} | {s['update_ms_median']:.3f} | {s['update_ms_p99']:.3f} | {s['triangles_median']:.0f} "
                   f"| {s['rms_error_median']:.3f} | {s['max_error_median']:.2f} |")
    out.append("")
budgeted = [n for n in rows if rows[n].get("budget_ms", 0) > 0]
if budgeted:
    out.append("**Time budgets (met when p99 <= 1.1 B + 0.1 ms, docs/surface.md; wall time, and the update thread's CPU time)**\n")
    out.append("| run | budget ms | wall median | wall p99 | CPU p99 | met (wall) | met (CPU) | triangles | splits+merges/frame | RMS error m | max screen px |")
    out.append("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for n in budgeted:
        s = rows[n]
        out.append(f"| {n} | {s['budget_ms']} | {s['update_ms_median']:.3f} | {s['update_ms_p99']:.3f} "
                   f"| {s.get('update_cpu_ms_p99', float('nan')):.3f} | {s.get('time_budget_met', '')} "
                   f"| {s.get('time_budget_met_cpu', '')} | {s['triangles_median']:.0f} | {s['changes_per_frame_median']:.0f} "
                   f"| {s['rms_error_median']:.3f} | {s['max_screen_error_px_median']:.2f} |")
    out.append("")
paths = [n for n in rows if n.startswith("default_") and rows[n].get("budget_ms", 0) == 0]
if paths:
    out.append("**Default terrain, the paths in tests/data/paths**\n")
    out.append("| path | threshold | budget ms | update ms median | p99 | max | triangles | RMS error m | max screen px | budget stops | budget met |")
    out.append("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for n in paths:
        s = rows[n]
        met = s.get("time_budget_met", "")
        out.append(f"| {n[len('default_'):]} | {s['threshold']} | {s['budget_ms']} | {s['update_ms_median']:.3f} | {s['update_ms_p99']:.3f} "
                   f"| {s['update_ms_max']:.2f} | {s['triangles_median']:.0f} | {s['rms_error_median']:.3f} "
                   f"| {s['max_screen_error_px_median']:.2f} | {s['time_budget_stops']} | {met} |")
print("\n".join(out))
