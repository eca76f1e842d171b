// The figures of a run (frame_loop.h) as the front ends print them, every median and percentile
// by stats.h's quantile: `ridge report`'s per-mode figures (docs/report_method.md, "Definitions"; also
// game_pop's) and `ridge bench lod`'s summary (docs/cli.md). The field names are what scripts/
// and docs/ read: add fields, do not rename them.
#pragma once

#include "ridgeline/bench/frame_loop.h"

namespace ridgeline::bench {

/// `ridge report`'s figures of one mode along one path: medians of the per-frame series, maxima
/// of the measured errors, jumps and pops (null where a series is empty or the mode does not
/// geomorph), then the technique's summary fields.
Json report_figures(const Run& run);

/// `ridge bench lod`'s summary of one run: medians, 99th percentiles and maxima of the update
/// and output times, the triangles, the changes, the upload and the memory, and the medians and
/// maxima of the measured errors (0 when no frame was measured; null for a figure the technique
/// does not report), then the technique's summary fields.
Json lod_figures(const Run& run);

/// Sets every field of `more` in `into` (in its order; existing fields are overwritten).
void append(Json& into, const Json& more);

/// Whether a time budget of `budget_ms` was held: the 99th percentile of the update's wall time
/// (time_budget_met) and of its thread-CPU time (time_budget_met_cpu) at most 1.1 x budget + 0.1 ms.
Json time_budget_figures(const Run& run, double budget_ms);

}  // namespace ridgeline::bench
